/**
 * A three.js loader of .pln files (spec/pln.md), in the style of three.js's PLYLoader:
 *
 *   import { PLNLoader } from 'planefmt-js/three/PLNLoader.mjs';
 *   new PLNLoader().load('part.pln', (group) => scene.add(group));
 *   const group = new PLNLoader().parse(arrayBuffer);
 *
 * `parse` returns a THREE.Group (the file) holding one THREE.Group per object, nested as the
 * objects' parents say, each with its transform (§8) as its matrix, and in each object one
 * THREE.Mesh per decoded part group: an indexed BufferGeometry with the positions, the triangles,
 * computed vertex normals and, where the file colours the group (cOLR, §10.1), a vertex colour
 * per triangle (sRGB in the file, linear in the attribute, as three.js expects). The material is a
 * MeshStandardMaterial with flat shading, both sides drawn, one per mesh (a viewer may recolour each part).
 *
 * userData of the returned group: `header`, `chunks`, `records` (version 6), `metadata` (mETA, and a version 5 header's up axis), `findings`, `groups`
 * (per group in file order: {index, kind, kindName, object, references, triangles, source}, source
 * a copy's source group or null), `upAxis` ('Y', 'Z' or null: the header's in version 5, mETA's before) and `file` (readPln's result). A
 * mesh's userData: {groupIndex, kind, kindName, object, source}. A copy (kind 11, §9.15) is a mesh
 * of its source's triangles in the copy's object (placed by its transform), coloured by its own cOLR. The loader does not turn a Z-up file Y-up; a viewer may (§10.3).
 *
 * Decoding uses ../src/browser.mjs (fflate inflates, brotli-dec-wasm decodes Brotli): in a browser,
 * an import map resolves `three`, `fflate` and `brotli-dec-wasm/web`; in Node, node_modules does. An invalid file raises readPln's PlnError
 * (through onError in `load`).
 */
import {
  BufferGeometry, Color, FileLoader, Float32BufferAttribute, Group, Loader, Mesh,
  MeshStandardMaterial, SRGBColorSpace, Uint32BufferAttribute, DoubleSide,
} from 'three';
import { readPln } from '../src/browser.mjs';

/** spec §9.3's kinds. */
export const KIND_NAMES = [
  'convex solid', 'cells', 'tree', 'pseudo-convex patch', 'pseudo-concave patch', 'sealed surface',
  'shell', 'shell tree', 'shell tree with parallelograms', 'shell walk', 'shell walk with multi-parallelograms',
  'copy', 'shell walk with reflections', 'shell walk from the later gate corner',
];

export class PLNLoader extends Loader {
  /** @param {import('three').LoadingManager} [manager] */
  constructor(manager) {
    super(manager);
    /** @type {object} options passed to readPln (e.g. {limits}) */
    this.readOptions = {};
  }

  /**
   * @param {string} url
   * @param {(group: Group) => void} onLoad
   * @param {(event: ProgressEvent) => void} [onProgress]
   * @param {(err: unknown) => void} [onError]
   */
  load(url, onLoad, onProgress, onError) {
    const loader = new FileLoader(this.manager);
    loader.setPath(this.path);
    loader.setResponseType('arraybuffer');
    loader.setRequestHeader(this.requestHeader);
    loader.setWithCredentials(this.withCredentials);
    loader.load(url, (buffer) => {
      try {
        onLoad(this.parse(/** @type {ArrayBuffer} */ (buffer)));
      } catch (e) {
        if (onError) onError(e); else console.error(e);
        this.manager.itemError(url);
      }
    }, onProgress, onError);
  }

  /**
   * @param {ArrayBuffer | Uint8Array} data the whole file
   * @returns {Group}
   */
  parse(data) {
    const file = readPln(data, this.readOptions);
    const root = new Group();
    root.name = 'pln';
    /** @type {Group[]} */
    const nodes = [];
    const groupObject = new Map();
    file.container.groups.forEach((/** @type {any} */ g) => groupObject.set(g.index, g.object));
    file.objects.forEach((o, k) => {
      const node = new Group();
      node.name = o.name;
      node.userData.objectIndex = k;
      if (o.transform) {
        // row by row, column vectors (§8): Matrix4.set takes row-major too
        node.matrix.set(...(/** @type {[number, number, number, number, number, number, number, number, number, number, number, number, number, number, number, number]} */ (o.transform)));
        node.matrix.decompose(node.position, node.quaternion, node.scale);
        node.matrixAutoUpdate = false; // keep shears exactly
      }
      (o.parent === null ? root : nodes[o.parent]).add(node);
      nodes.push(node);
      for (const g of o.groups) node.add(groupMesh(g, o.name));
    });
    root.userData = {
      header: file.header,
      chunks: file.chunks,
      // version 6: raw bytes per record type in the body segments (the chunks are PHDR, BODY and PEND)
      records: file.container.records,
      metadata: file.metadata,
      findings: [...file.findings],
      // a version 5 header's up axis, or mETA's up_axis before version 5 (readPln's metadata holds either, §10.3)
      upAxis: file.metadata.up_axis === 'Y' || file.metadata.up_axis === 'Z' ? file.metadata.up_axis : null,
      groups: file.container.groups.map((/** @type {any} */ g) => ({
        index: g.index,
        kind: g.kind,
        kindName: KIND_NAMES[g.kind] ?? `kind ${g.kind}`,
        object: g.object,
        references: g.refs.length,
        source: g.kind === 11 && g.data ? g.data.source : null,
        triangles: file.meshes[g.index] ? /** @type {any} */ (file.meshes[g.index]).indices.length / 3 : 0,
      })),
      file,
    };
    return root;
  }
}

const srgb = new Color();

/**
 * @param {import('../src/index.mjs').MeshGroup} g
 * @param {string} objectName
 */
function groupMesh(g, objectName) {
  const geometry = new BufferGeometry();
  const T = g.indices.length / 3;
  let alpha = false;
  if (g.faceColors) {
    // a colour per triangle: each triangle gets its own three vertices
    const positions = new Float32Array(9 * T);
    const colors = new Float32Array(12 * T);
    for (let t = 0; t < T; t++) {
      const c = g.faceColors;
      srgb.setRGB(c[4 * t] / 255, c[4 * t + 1] / 255, c[4 * t + 2] / 255, SRGBColorSpace);
      if (c[4 * t + 3] < 255) alpha = true;
      for (let k = 0; k < 3; k++) {
        const v = g.indices[3 * t + k];
        positions.set(g.positions.subarray(3 * v, 3 * v + 3), 9 * t + 3 * k);
        colors.set([srgb.r, srgb.g, srgb.b, c[4 * t + 3] / 255], 12 * t + 4 * k);
      }
    }
    const index = new Uint32Array(3 * T);
    for (let i = 0; i < index.length; i++) index[i] = i;
    geometry.setAttribute('position', new Float32BufferAttribute(positions, 3));
    if (alpha) geometry.setAttribute('color', new Float32BufferAttribute(colors, 4));
    else geometry.setAttribute('color', new Float32BufferAttribute(colors.filter((_, i) => i % 4 !== 3), 3));
    geometry.setIndex(new Uint32BufferAttribute(index, 1));
  } else {
    geometry.setAttribute('position', new Float32BufferAttribute(g.positions, 3));
    geometry.setIndex(new Uint32BufferAttribute(g.indices, 1));
  }
  geometry.computeVertexNormals();
  geometry.computeBoundingBox();
  geometry.computeBoundingSphere();
  const material = new MeshStandardMaterial({
    color: g.faceColors ? 0xffffff : 0xb4b4b4,
    flatShading: true,
    vertexColors: !!g.faceColors,
    transparent: alpha,
    side: DoubleSide, // patches and open shells: both sides
    metalness: 0.05,
    roughness: 0.7,
  });
  const mesh = new Mesh(geometry, material);
  mesh.name = `group ${g.index}`;
  mesh.userData = {
    groupIndex: g.index, kind: g.kind, kindName: KIND_NAMES[g.kind] ?? `kind ${g.kind}`, object: objectName, source: g.source,
  };
  return mesh;
}
