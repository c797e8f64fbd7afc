// Copies (kind 11, spec §9.15, version 4.2) on files assembled here: copies of a convex cube (kind
// 0), of shell walks (kinds 9 and 10, their bodies taken from golden files) and of a patch with role
// bits, each decoded to its source's surface in the copy's own object, coloured by its own cOLR;
// the report (conformance/README.md: a copy listed as stored, with "source"); the three.js loader;
// every check of §9.15 in its order, and kind 11 against the versions of §9.3.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import * as THREE from 'three';
import { readPln as readNode } from '../src/node.mjs';
import { readPln as readBrowser } from '../src/browser.mjs';
import { conformanceJson } from '../src/report.mjs';
import { PLNLoader, KIND_NAMES } from '../three/PLNLoader.mjs';
import { golden, varint, common, file4, groupBody, expectBoth as expect } from './files.mjs';

/**
 * A file of version 4.2 unless `version` says otherwise (files.mjs's file4): planes, objects,
 * groups (each its object, kind and body), cOLR chunks.
 * @param {Omit<import('./files.mjs').File4, 'version'> & {version?: [number, number]}} f
 */
const build = ({ version = [4, 2], ...f }) => file4({ ...f, version });

/** The triplet (ν, φ, h) of the plane with unit normal n at distance h. @param {number[]} n @param {number} h */
function triplet(n, h) {
  const nu = Math.acos(n[2]);
  let phi = Math.atan2(n[1], n[0]);
  if (phi < 0) phi += 2 * Math.PI;
  if (nu === 0 || nu === Math.PI) phi = 0;
  return [nu, phi, h];
}

/** The unit cube's six planes: -z, +z, -y, +y, -x, +x. */
const CUBE = [
  ...triplet([0, 0, -1], 0), ...triplet([0, 0, 1], 1), ...triplet([0, -1, 0], 0),
  ...triplet([0, 1, 0], 1), ...triplet([-1, 0, 0], 0), ...triplet([1, 0, 0], 1),
];
const SIX = [0, 1, 2, 3, 4, 5];

/** A copy's body: the common body and the source's varint (and `tail`). @param {number[]} refs @param {number | bigint} s */
const copyBody = (refs, s, { bounding = /** @type {number[]} */ ([]), tail = /** @type {number[]} */ ([]) } = {}) => [...common(refs, bounding), ...varint(s), ...tail];

const translate = (/** @type {number} */ x, /** @type {number} */ y, /** @type {number} */ z) => [1, 0, 0, x, 0, 1, 0, y, 0, 0, 1, z];

/**
 * The planes and the first group of a golden file (its body decompressed), to copy.
 * @param {string} name
 */
function goldenGroup(name) {
  const bytes = golden(name);
  const file = readNode(bytes);
  const { kind, body } = groupBody(bytes, 0, file);
  const g = file.container.groups[0];
  assert.equal(file.header.coding, 0, name); // float32 planes: build(…, coding: 0) writes them alike
  return { planes: file.planes, coding: /** @type {0} */ (0), kind, body: [...body], refs: [...g.refs], json: conformanceJson(file) };
}

/** The world positions of a decoded group's vertices. @param {number[]} M 12 entries @param {Float64Array} p */
function moved(M, p) {
  const out = [];
  for (let v = 0; v < p.length; v += 3) {
    for (let r = 0; r < 3; r++) out.push(M[4 * r] * p[v] + M[4 * r + 1] * p[v + 1] + M[4 * r + 2] * p[v + 2] + M[4 * r + 3]);
  }
  return out;
}

/**
 * Checks a file whose group `copy` copies group `source`: listed as stored, decoded to the same
 * surface, the same in both entries; returns the node entry's result.
 * @param {Uint8Array} bytes @param {number} copy @param {number} source
 */
function checkCopy(bytes, copy, source) {
  const file = readNode(bytes);
  const json = conformanceJson(file);
  assert.deepEqual(json.findings, []);
  const g = json.groups[copy];
  const s = json.groups[source];
  assert.deepEqual(Object.keys(g).sort(), ['bounding', 'index', 'kind', 'object', 'refs', 'source']);
  assert.equal(g.kind, 11);
  assert.equal(g.source, source);
  assert.equal(g.index, copy);
  assert.deepEqual(g.refs, s.refs);
  assert.deepEqual(g.bounding, s.bounding);
  const geo = /** @type {any} */ (json.geometry);
  assert.deepEqual(geo.groups[copy], geo.groups[source], 'the summary of the source');
  const mc = /** @type {any} */ (file.meshes[copy]);
  const ms = /** @type {any} */ (file.meshes[source]);
  assert.equal(mc.kind, 11);
  assert.equal(mc.source, source);
  assert.equal(ms.source, null);
  assert.deepEqual([...mc.positions64], [...ms.positions64]);
  assert.deepEqual([...mc.positions], [...ms.positions]);
  assert.deepEqual([...mc.indices], [...ms.indices]);
  assert.deepEqual([...mc.faceRefs], [...ms.faceRefs]);
  assert.deepEqual(conformanceJson(readBrowser(bytes)), json, 'browser entry');
  return { file, json };
}

test('§9.15: copies of a convex cube, each placed by its own object', () => {
  const mirror = [-1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0]; // det < 0
  const turn = [0, -2, 0, 5, 2, 0, 0, -1, 0, 0, 2, 0.5]; // a quarter turn about z, scale 2
  const objects = [null, translate(2, 0, 0), turn, mirror];
  const bytes = build({
    planes: CUBE, objects,
    groups: [
      { object: 0, kind: 0, body: common(SIX) },
      { object: 1, kind: 11, body: copyBody(SIX, 0) },
      { object: 2, kind: 11, body: copyBody(SIX, 0), method: 1 },
      { object: 3, kind: 11, body: copyBody(SIX, 0), method: 2 },
      { object: 0, kind: 11, body: copyBody(SIX, 0) }, // in the source's own object: the same place
    ],
  });
  const { file, json } = checkCopy(bytes, 1, 0);
  for (const k of [2, 3, 4]) checkCopy(bytes, k, 0);
  const cube = /** @type {any} */ (json.geometry).groups[0];
  assert.equal(cube.vertices, 8);
  assert.equal(cube.triangles, 12);
  assert.ok(Math.abs(cube.volume - 1) < 1e-12, 'a copy of a solid has its volume');
  assert.deepEqual(json.groups.map((/** @type {any} */ g) => g.object), [0, 1, 2, 3, 0]);
  // world: the cube at [0,1]³, at [2,3]×[0,1]², turned and scaled to [3,5]×[-1,1]×[0.5,2.5], mirrored to [-1,0]×[0,1]²
  const box = /** @type {any} */ (json.geometry).world_bbox;
  const near = (/** @type {number[]} */ a, /** @type {number[]} */ b) => a.every((v, i) => Math.abs(v - b[i]) < 1e-12);
  assert.ok(near(box[0], [-1, -1, 0]) && near(box[1], [5, 1, 2.5]), JSON.stringify(box));
  const world = file.mesh();
  assert.equal(world.indices.length, 5 * 36);
  assert.deepEqual([...new Set(world.groupOfTriangle)], [0, 4, 1, 2, 3]); // by object, then group
  // every copy's world triangles face outwards: the signed volume of each is +1, +8 (scale 2), +1
  const vol = (/** @type {number} */ gi) => {
    let v = 0;
    const p = world.positions64;
    world.indices.forEach((_, t) => {
      if (t % 3 || world.groupOfTriangle[t / 3] !== gi) return;
      const [a, b, c] = [3 * world.indices[t], 3 * world.indices[t + 1], 3 * world.indices[t + 2]];
      v += (p[a] * (p[b + 1] * p[c + 2] - p[b + 2] * p[c + 1]) - p[a + 1] * (p[b] * p[c + 2] - p[b + 2] * p[c])
        + p[a + 2] * (p[b] * p[c + 1] - p[b + 1] * p[c])) / 6;
    });
    return v;
  };
  for (const [gi, want] of [[0, 1], [1, 1], [2, 8], [3, 1], [4, 1]]) assert.ok(Math.abs(vol(gi) - want) < 1e-9, `group ${gi}: ${vol(gi)}`);
  // the copy in object 1: the source's vertices moved by (2, 0, 0)
  const p0 = /** @type {any} */ (file.meshes[0]).positions64;
  const p1 = world.positions64.subarray(3 * 16, 3 * 24); // object 0's two groups first, 8 vertices each
  assert.deepEqual([...p1], moved(translate(2, 0, 0), p0));
});

test('§9.15: copies of shell walks (kinds 9 and 10 from golden files), with their own colours', () => {
  for (const name of ['shell_walk_cube_v4_1.pln', 'shell_walk_torus_v4_1.pln', 'shell_walk_multi_sphere_v4_2.pln', 'shell_walk_multi_tables_v4_2.pln']) {
    const src = goldenGroup(name);
    assert.ok(src.kind === 9 || src.kind === 10, name);
    const bounding = src.json.groups[0].bounding;
    const m = src.refs.length;
    const red = [200, 30, 30, 255];
    const rgba = [];
    for (let i = 0; i < m; i++) rgba.push(...(i % 2 ? red : [10, 20, 30 + i % 200, 128]));
    const bytes = build({
      planes: src.planes, coding: 0, objects: [null, translate(0, 0, 10), translate(-3, 4, 0)],
      groups: [
        { object: 0, kind: src.kind, body: src.body },
        { object: 1, kind: 11, body: copyBody(src.refs, 0, { bounding }) },
        { object: 2, kind: 11, body: copyBody(src.refs, 0, { bounding }), method: 2 },
      ],
      colours: [{ group: 1, rgba }],
    });
    const { file, json } = checkCopy(bytes, 1, 0);
    checkCopy(bytes, 2, 0);
    // the source as its golden file reports it, the copies' summaries its summary
    assert.deepEqual(json.groups[0].shell, src.json.groups[0].shell, name);
    assert.deepEqual(/** @type {any} */ (json.geometry).groups[1], /** @type {any} */ (src.json.geometry).groups[0], name);
    assert.equal(/** @type {any} */ (json.geometry).groups[1].volume, null, 'a copy of a shell: no volume');
    // colours: the copy's own cOLR; neither the source nor the other copy takes it
    const m0 = /** @type {any} */ (file.meshes[0]);
    const m1 = /** @type {any} */ (file.meshes[1]);
    const m2 = /** @type {any} */ (file.meshes[2]);
    assert.equal(m0.faceColors, null);
    assert.equal(m2.faceColors, null);
    const T = m1.indices.length / 3;
    for (let t = 0; t < T; t++) {
      const r = m1.faceRefs[t] < 0 ? m - 1 : m1.faceRefs[t];
      assert.deepEqual([...m1.faceColors.subarray(4 * t, 4 * t + 4)], rgba.slice(4 * r, 4 * r + 4), `${name} triangle ${t}`);
    }
    // placed by the copy's object
    const box = /** @type {any} */ (json.geometry).world_bbox;
    const sb = /** @type {any} */ (src.json.geometry).groups[0].bbox;
    const d = Math.hypot(...[0, 1, 2].map((i) => sb[1][i] - sb[0][i]));
    const want = [[Math.min(sb[0][0], sb[0][0] - 3), sb[0][1], sb[0][2]], [sb[1][0], sb[1][1] + 4, sb[1][2] + 10]];
    for (let e = 0; e < 2; e++) for (let i = 0; i < 3; i++) assert.ok(Math.abs(box[e][i] - want[e][i]) <= 1e-6 * d, `${name} world box`);
  }
});

test('§9.15: a copy of a patch keeps its role bits; a copy of a colour-less source coloured, a coloured source\'s copy not', () => {
  // a pseudo-convex patch (kind 3): the top face (+z, local 1) of the cube, the others bounding
  const bounding = [0, 2, 3, 4, 5];
  const bytes = build({
    planes: CUBE, objects: [null, translate(0, 0, 1)],
    groups: [
      { object: 0, kind: 3, body: common(SIX, bounding) },
      { object: 1, kind: 11, body: copyBody(SIX, 0, { bounding }) },
    ],
    colours: [{ group: 0, rgba: Array(24).fill(77) }],
  });
  const { file, json } = checkCopy(bytes, 1, 0);
  assert.deepEqual(json.groups[1].bounding, bounding);
  const s = /** @type {any} */ (json.geometry).groups[1];
  assert.equal(s.triangles, 2);
  assert.equal(s.volume, null);
  assert.ok(Math.abs(s.area_vector[2] - 1) < 1e-12);
  assert.notEqual(/** @type {any} */ (file.meshes[0]).faceColors, null);
  assert.equal(/** @type {any} */ (file.meshes[1]).faceColors, null);
});

test('§9.15: several sources and copies interleaved; a copy names its source, not the group before it', () => {
  const src = goldenGroup('shell_walk_cube_v4_1.pln');
  // the cube's planes after the walk's: refs shifted
  const n = src.planes.length / 3;
  const shifted = SIX.map((r) => r + n);
  const bytes = build({
    planes: [...src.planes, ...CUBE], coding: 0, objects: [null, translate(5, 0, 0)],
    groups: [
      { object: 0, kind: 0, body: common(shifted) },
      { object: 0, kind: src.kind, body: src.body },
      { object: 1, kind: 11, body: copyBody(src.refs, 1) },
      { object: 1, kind: 11, body: copyBody(shifted, 0) },
      { object: 1, kind: 11, body: copyBody(src.refs, 1) },
    ],
  });
  checkCopy(bytes, 2, 1);
  checkCopy(bytes, 3, 0);
  const { json } = checkCopy(bytes, 4, 1);
  assert.deepEqual(json.groups.map((/** @type {any} */ g) => g.source ?? null), [null, null, 1, 0, 1]);
  // read without decoding: the copies listed, no geometry
  const bare = readNode(bytes, { decode: false });
  assert.deepEqual(bare.meshes, [null, null, null, null, null]);
  assert.equal(conformanceJson(bare).geometry, null);
  assert.deepEqual(conformanceJson(bare).groups, json.groups);
});

test('§9.15 errors: a source not before the copy, a copy of a copy (BAD_GROUP_STRUCTURE)', () => {
  const cube = { kind: 0, body: common(SIX) };
  const copy = (/** @type {number | bigint} */ s, /** @type {any} */ o = {}) => ({ kind: 11, body: copyBody(SIX, s, o) });
  expect(build({ planes: CUBE, groups: [cube, copy(0)] }), 'ok', 'a copy of group 0');
  expect(build({ planes: CUBE, groups: [cube, copy(1)] }), 'BAD_GROUP_STRUCTURE', 'itself');
  expect(build({ planes: CUBE, groups: [cube, copy(2)] }), 'BAD_GROUP_STRUCTURE', 'a later group');
  expect(build({ planes: CUBE, groups: [copy(0)] }), 'BAD_GROUP_STRUCTURE', 'group 0 copying itself');
  expect(build({ planes: CUBE, groups: [cube, copy(2), cube] }), 'BAD_GROUP_STRUCTURE', 'a later group that exists');
  // s is a varint (§9.15), not a varint32: 2^32 and 2^64 − 1 are well formed, and not earlier groups
  expect(build({ planes: CUBE, groups: [cube, copy(2 ** 32)] }), 'BAD_GROUP_STRUCTURE', '2^32');
  expect(build({ planes: CUBE, groups: [cube, copy(2n ** 64n - 1n)] }), 'BAD_GROUP_STRUCTURE', '2^64 − 1');
  expect(build({ planes: CUBE, groups: [cube, copy(0), copy(1)] }), 'BAD_GROUP_STRUCTURE', 'a copy of a copy');
  expect(build({ planes: CUBE, groups: [cube, copy(0), copy(0), copy(2)] }), 'BAD_GROUP_STRUCTURE', 'a copy of a later copy');
  // step 2 before step 4: a copy of a copy with other references is still BAD_GROUP_STRUCTURE, and
  // the error names the source, not the references
  const msg = (/** @type {Uint8Array} */ b) => { try { readNode(b); } catch (e) { return /** @type {Error} */ (e).message; } return ''; };
  assert.match(msg(build({ planes: CUBE, groups: [cube, copy(0), { kind: 11, body: copyBody([0, 1], 1) }] })), /itself a copy/);
  assert.match(msg(build({ planes: CUBE, groups: [cube, { kind: 11, body: copyBody([0, 1], 5) }] })), /not an earlier group/);
});

test('§9.15 errors: references or role bits other than the source\'s (BAD_GROUP_STRUCTURE)', () => {
  const cube = { kind: 0, body: common(SIX) };
  const planes = [...CUBE, ...triplet([0, 0, 1], 2)];
  const cases = /** @type {[string, number[], number[]][]} */ ([
    ['fewer references', [0, 1, 2, 3, 4], []],
    ['more references', [0, 1, 2, 3, 4, 5, 6], []],
    ['a repeated reference more', [0, 1, 2, 3, 4, 5, 5], []],
    ['one other reference', [0, 1, 2, 3, 4, 6], []],
    ['a repeat for another', [0, 1, 2, 3, 4, 4], []],
    ['a role bit set', SIX, [0]],
    ['the last role bit set', SIX, [5]],
  ]);
  for (const [what, refs, bounding] of cases) {
    expect(build({ planes, groups: [cube, { kind: 11, body: copyBody(refs, 0, { bounding }) }] }), 'BAD_GROUP_STRUCTURE', what);
  }
  // a kind 0 source whose role bits a writer should not have set: the copy still must have them
  const marked = { kind: 0, body: common(SIX, [2]) };
  expect(build({ planes, groups: [marked, { kind: 11, body: copyBody(SIX, 0, { bounding: [2] }) }] }), 'ok', 'the same stray bit');
  expect(build({ planes, groups: [marked, { kind: 11, body: copyBody(SIX, 0) }] }), 'BAD_GROUP_STRUCTURE', 'a role bit cleared');
  // the references compared in order: a source with a repeated reference
  const rep = [0, 1, 1, 2, 3, 4, 5];
  expect(build({ planes, groups: [{ kind: 0, body: common(rep) }, { kind: 11, body: copyBody(rep, 0) }] }), 'ok', 'a repeat, copied');
  expect(build({ planes, groups: [{ kind: 0, body: common(rep) }, { kind: 11, body: copyBody([0, 1, 2, 2, 3, 4, 5], 0) }] }),
    'BAD_GROUP_STRUCTURE', 'the repeat elsewhere');
  // a walk's source: one role bit differs
  const src = goldenGroup('shell_walk_torus_v4_1.pln');
  const b = src.json.groups[0].bounding;
  const groups = [{ kind: src.kind, body: src.body }];
  expect(build({ planes: src.planes, coding: 0, groups: [...groups, { kind: 11, body: copyBody(src.refs, 0, { bounding: b }) }] }), 'ok', 'walk copy');
  const toggled = b.includes(0) ? b.filter((/** @type {number} */ v) => v !== 0) : [0, ...b];
  expect(build({ planes: src.planes, coding: 0, groups: [...groups, { kind: 11, body: copyBody(src.refs, 0, { bounding: toggled }) }] }),
    'BAD_GROUP_STRUCTURE', 'walk copy, role bit 0 toggled');
});

test('§9.15 errors: a trailing byte, a truncated or bad varint (BAD_PAYLOAD), before the source is looked at', () => {
  const cube = { kind: 0, body: common(SIX) };
  const g = (/** @type {number[]} */ body) => build({ planes: CUBE, groups: [cube, { kind: 11, body }] });
  expect(g([...common(SIX), 0, 0]), 'BAD_PAYLOAD', 'a byte after the source');
  expect(g([...common(SIX), 0, 0xff, 0xff]), 'BAD_PAYLOAD', 'bytes after the source');
  expect(g([...common(SIX)]), 'BAD_PAYLOAD', 'no source');
  expect(g([...common(SIX), 0x80]), 'BAD_PAYLOAD', 'ends inside the varint');
  expect(g([...common(SIX), 0x81, 0x80]), 'BAD_PAYLOAD', 'ends inside a longer varint');
  expect(g([...common(SIX), 0x80, 0x00]), 'BAD_PAYLOAD', 'a varint not minimal');
  expect(g([...common(SIX), ...Array(9).fill(0xff), 0x02]), 'BAD_PAYLOAD', 'a varint of 2^64');
  // check 1 before check 2 and check 4: a later source, or other references, with a byte after it
  expect(g([...common(SIX), 5, 0]), 'BAD_PAYLOAD', 'a later source and a trailing byte');
  expect(g([...common(SIX), 0x85]), 'BAD_PAYLOAD', 'a later source, truncated');
  expect(g([...common([0, 1]), 0, 0]), 'BAD_PAYLOAD', 'other references and a trailing byte');
  expect(build({ planes: CUBE, groups: [cube, { kind: 11, body: copyBody(SIX, 0) }, { kind: 11, body: copyBody(SIX, 1, { tail: [0] }) }] }),
    'BAD_PAYLOAD', 'a copy of a copy with a trailing byte');
  // the common body first (§9.1, §9.2): a bad reference before a truncated source
  expect(g([...common([0, 1, 2, 3, 4, 9]), 0x80]), 'BAD_PLANE_REFERENCE', 'a plane not defined');
  expect(g([...varint(6), 0, 1, 1, 1, 1, 1]), 'BAD_PAYLOAD', 'ends inside the roles');
  // a compressed body ends alike
  expect(build({ planes: CUBE, groups: [cube, { kind: 11, body: [...common(SIX), 0, 0], method: 1 }] }), 'BAD_PAYLOAD', 'zlib');
  expect(build({ planes: CUBE, groups: [cube, { kind: 11, body: [...common(SIX), 0x80], method: 2 }] }), 'BAD_PAYLOAD', 'Brotli');
});

test('§9.3: kind 11 in 4.2 and later minors; unknown in 4.0, 4.1 and 3.4; skipped in 3.5, with a copy of a skipped source', () => {
  const groups = [{ kind: 0, body: common(SIX) }, { kind: 11, body: copyBody(SIX, 0) }];
  expect(build({ planes: CUBE, groups, version: [4, 2] }), 'ok', '4.2');
  for (const v of /** @type {[number, number][]} */ ([[4, 1], [4, 0], [3, 4]])) {
    expect(build({ planes: CUBE, groups, version: v }), 'UNKNOWN_GROUP_KIND', v.join('.'));
    // before its kind data is read: also a broken copy
    expect(build({ planes: CUBE, groups: [groups[0], { kind: 11, body: [...common(SIX), 0x80] }], version: v }), 'UNKNOWN_GROUP_KIND', `${v.join('.')}, broken`);
  }
  // 4.3: a copy read as in 4.2
  const r43 = readNode(build({ planes: CUBE, groups, version: [4, 3] }));
  assert.deepEqual([...r43.findings], ['NEWER_MINOR_VERSION']);
  assert.equal(conformanceJson(r43).groups[1].source, 0);
  assert.equal(/** @type {any} */ (r43.meshes[1]).indices.length, 36);
  // 3.5: kind 11 is a kind of no 3.x version the reader knows: skipped, its kind data unread
  const r35 = readNode(build({ planes: CUBE, groups: [groups[0], { kind: 11, body: [...common(SIX), 0x80, 7, 7] }], version: [3, 5] }));
  assert.deepEqual([...r35.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  assert.equal(r35.meshes[1], null);
  assert.deepEqual(conformanceJson(r35).groups[1], { index: 1, object: 0, kind: 11, refs: SIX, bounding: [] });
});

test('§9.15 step 3: a copy of a skipped group is skipped; steps 1 and 2 still apply, step 4 does not', () => {
  // 4.3: kind 12 is skipped (a kind of a newer minor), and so is a copy of it
  const k12 = { kind: 12, body: [...common(SIX), 1, 2, 3] };
  const file = (/** @type {any[]} */ groups) => build({ planes: CUBE, groups, version: [4, 3] });
  const r = readNode(file([k12, { kind: 11, body: copyBody(SIX, 0) }, { kind: 0, body: common(SIX) }, { kind: 11, body: copyBody(SIX, 2) }]));
  assert.deepEqual([...r.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  assert.deepEqual(r.meshes.map((m) => m !== null), [false, false, true, true]);
  const json = conformanceJson(r);
  assert.deepEqual(json.groups[1], { index: 1, object: 0, kind: 11, refs: SIX, bounding: [], source: 0 });
  assert.deepEqual(/** @type {any} */ (json.geometry).groups.map((/** @type {any} */ g) => g !== null), [false, false, true, true]);
  // other references and role bits than the skipped source's: not compared (step 4 after step 3)
  expect(file([k12, { kind: 11, body: copyBody([0, 1, 2], 0, { bounding: [1] }) }]), 'ok', 'other references, a skipped source');
  // steps 1 and 2 before step 3
  expect(file([k12, { kind: 11, body: copyBody(SIX, 0, { tail: [0] }) }]), 'BAD_PAYLOAD', 'a trailing byte, a skipped source');
  expect(file([k12, { kind: 11, body: copyBody(SIX, 1) }]), 'BAD_GROUP_STRUCTURE', 'a later source');
  // a copy of a skipped copy cannot arise: a copy is skipped only with its source, itself not a copy;
  // a copy of that skipped copy is a copy of a copy
  expect(file([k12, { kind: 11, body: copyBody(SIX, 0) }, { kind: 11, body: copyBody(SIX, 1) }]), 'BAD_GROUP_STRUCTURE', 'a copy of a skipped copy');
});

test('§9.15: a source\'s geometry error is its own, before its copies; a copy\'s cOLR counts its own references', () => {
  // the cube without its +x plane: unbounded
  const five = [0, 1, 2, 3, 4];
  expect(build({ planes: CUBE, groups: [{ kind: 0, body: common(five) }, { kind: 11, body: copyBody(five, 0) }] }), 'UNBOUNDED_POLYTOPE', 'unbounded source');
  const groups = [{ kind: 0, body: common(SIX) }, { kind: 11, body: copyBody(SIX, 0) }];
  expect(build({ planes: CUBE, groups, colours: [{ group: 1, rgba: Array(20).fill(1) }] }), 'BAD_COLOURS', 'five colours for six references');
  const one = build({ planes: CUBE, groups, colours: [{ group: 1, rgba: Array(24).fill(9) }] });
  const fc = /** @type {any} */ (readNode(one).meshes[1]).faceColors;
  assert.equal(fc.length, 4 * 12);
});

test('PLNLoader: a copy is a mesh of its source\'s triangles in its own object, with its own colours', () => {
  const src = goldenGroup('shell_walk_cube_v4_1.pln');
  const m = src.refs.length;
  const bytes = build({
    planes: src.planes, coding: 0, objects: [null, translate(2, 0, 0)],
    groups: [{ object: 0, kind: src.kind, body: src.body }, { object: 1, kind: 11, body: copyBody(src.refs, 0) }],
    colours: [{ group: 1, rgba: Array(m).fill([200, 30, 30, 255]).flat() }],
  });
  const root = new PLNLoader().parse(bytes);
  root.updateMatrixWorld(true);
  /** @type {THREE.Mesh[]} */
  const meshes = [];
  root.traverse((o) => { if (/** @type {THREE.Mesh} */ (o).isMesh) meshes.push(/** @type {THREE.Mesh} */ (o)); });
  assert.equal(meshes.length, 2);
  const [a, b] = meshes;
  assert.equal(b.userData.kind, 11);
  assert.equal(b.userData.kindName, 'copy');
  assert.equal(KIND_NAMES[11], 'copy');
  assert.equal(b.userData.source, 0);
  assert.equal(a.userData.source, null);
  assert.equal(/** @type {THREE.Group} */ (b.parent).userData.objectIndex, 1);
  assert.equal(/** @type {any} */ (b.geometry.index).count, /** @type {any} */ (a.geometry.index).count);
  assert.ok(b.geometry.getAttribute('color'), 'the copy\'s own colours');
  assert.ok(!a.geometry.getAttribute('color'), 'the source has none');
  const ba = new THREE.Box3().setFromObject(a, true);
  const bb = new THREE.Box3().setFromObject(b, true);
  assert.ok(bb.min.clone().sub(ba.min).distanceTo(new THREE.Vector3(2, 0, 0)) < 1e-6);
  assert.ok(bb.max.clone().sub(ba.max).distanceTo(new THREE.Vector3(2, 0, 0)) < 1e-6);
  const info = root.userData.groups[1];
  assert.deepEqual({ kind: info.kind, kindName: info.kindName, source: info.source, triangles: info.triangles },
    { kind: 11, kindName: 'copy', source: 0, triangles: 12 });
  assert.equal(root.userData.groups[0].source, null);
});
