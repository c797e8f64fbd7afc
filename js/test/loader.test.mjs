// The three.js loader (three/PLNLoader.mjs) in Node, on every valid golden file: one mesh per
// decoded group with the decoder's triangles, the world bounding box of the scene graph equal to
// readPln's world-frame mesh (transforms applied), colours where the file has them, userData.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import * as THREE from 'three';
import { PLNLoader, KIND_NAMES } from '../three/PLNLoader.mjs';
import { readPln } from '../src/node.mjs';
import { VALID } from './files.mjs';

const files = fs.readdirSync(VALID).filter((f) => f.endsWith('.pln')).sort();

test('golden files are there', () => assert.ok(files.length >= 30, `${files.length} files in ${VALID}`));

for (const name of files) {
  test(`PLNLoader.parse ${name}`, () => {
    const bytes = fs.readFileSync(path.join(VALID, name));
    const file = readPln(bytes);
    const root = new PLNLoader().parse(bytes);
    root.updateMatrixWorld(true);
    /** @type {THREE.Mesh[]} */
    const meshes = [];
    root.traverse((o) => { if (/** @type {THREE.Mesh} */ (o).isMesh) meshes.push(/** @type {THREE.Mesh} */ (o)); });
    const decoded = file.meshes.filter((m) => m !== null);
    assert.equal(meshes.length, decoded.length, 'a mesh per decoded group');
    let objects = 0;
    root.traverse((o) => { if (o !== root && !(/** @type {THREE.Mesh} */ (o).isMesh)) objects++; });
    assert.equal(objects, file.objects.length, 'a THREE.Group per object');
    for (const mesh of meshes) {
      const g = /** @type {NonNullable<typeof decoded[0]>} */ (file.meshes[mesh.userData.groupIndex]);
      const geo = mesh.geometry;
      assert.equal(/** @type {THREE.BufferAttribute} */ (geo.index).count, g.indices.length, 'triangles');
      assert.ok(geo.getAttribute('normal'), 'normals');
      assert.equal(mesh.userData.kind, g.kind);
      assert.equal(mesh.userData.kindName, KIND_NAMES[g.kind]);
      assert.equal(!!geo.getAttribute('color'), !!g.faceColors, 'vertex colours where the file has colours');
      const mat = /** @type {THREE.MeshStandardMaterial} */ (mesh.material);
      assert.equal(mat.flatShading, true);
      assert.equal(mat.vertexColors, !!g.faceColors);
    }
    // transforms: the scene graph's world box is that of readPln's world-frame mesh
    const world = file.mesh();
    if (world.indices.length > 0) {
      const want = new THREE.Box3().setFromBufferAttribute(new THREE.BufferAttribute(world.positions, 3));
      const got = new THREE.Box3().setFromObject(root, true);
      const diag = want.min.distanceTo(want.max);
      assert.ok(got.min.distanceTo(want.min) <= 1e-6 * diag && got.max.distanceTo(want.max) <= 1e-6 * diag,
        `world box ${JSON.stringify(got)} against ${JSON.stringify(want)}`);
    }
    assert.deepEqual(root.userData.header, file.header);
    assert.deepEqual(root.userData.chunks, file.chunks);
    assert.equal(root.userData.groups.length, file.container.groups.length);
    assert.equal(root.userData.upAxis, file.metadata.up_axis ?? null);
  });
}

test('cube_colours.pln: sRGB colours become linear vertex colours', () => {
  const bytes = fs.readFileSync(path.join(VALID, 'cube_colours.pln'));
  const file = readPln(bytes);
  const root = new PLNLoader().parse(bytes);
  /** @type {THREE.Mesh | undefined} */
  let mesh;
  root.traverse((o) => { if (/** @type {THREE.Mesh} */ (o).isMesh) mesh = /** @type {THREE.Mesh} */ (o); });
  assert.ok(mesh);
  const g = /** @type {NonNullable<typeof file.meshes[0]>} */ (file.meshes[mesh.userData.groupIndex]);
  const fc = /** @type {Uint8Array} */ (g.faceColors);
  const col = mesh.geometry.getAttribute('color');
  const c = new THREE.Color();
  for (let t = 0; t < g.indices.length / 3; t++) {
    c.setRGB(col.getX(3 * t), col.getY(3 * t), col.getZ(3 * t)); // linear
    const s = c.getRGB(new THREE.Color(), THREE.SRGBColorSpace);
    assert.ok(Math.abs(s.r * 255 - fc[4 * t]) < 0.01 && Math.abs(s.g * 255 - fc[4 * t + 1]) < 0.01
      && Math.abs(s.b * 255 - fc[4 * t + 2]) < 0.01, `triangle ${t}`);
  }
});

test('load: a data URL to onLoad, an invalid file to onError', async () => {
  // three's FileLoader reports progress with ProgressEvent, which Node lacks
  /** @type {any} */ (globalThis).ProgressEvent ??= class extends Event {
    constructor(/** @type {string} */ type, /** @type {any} */ init = {}) { super(type); Object.assign(this, init); }
  };
  const bytes = fs.readFileSync(path.join(VALID, 'cube_v3.pln'));
  const url = (/** @type {Uint8Array} */ b) => `data:application/octet-stream;base64,${Buffer.from(b).toString('base64')}`;
  const root = await new PLNLoader().loadAsync(url(bytes));
  assert.equal(root.userData.groups.length, 1);
  const err = await new PLNLoader().loadAsync(url(bytes.subarray(0, 40))).then(() => null, (e) => e);
  assert.equal(err?.code, 'TRUNCATED');
});
