// Version 6.0 on files built here by hand from the design's words (v6-design.md until spec/pln.md has
// version 6): the compact header with r32 values, body segments in PHDR's tail and in BODY chunks,
// records dispatched to the payload readers of versions 1-5 with version 6's differences, the v6
// index; and every new check on damaged copies.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import zlib from 'node:zlib';
import { readPln as readNode, PlnError } from '../src/node.mjs';
import { readPln as readBrowser } from '../src/browser.mjs';
import { conformanceJson } from '../src/report.mjs';
import {
  varint, f32, common, header6, record, segment, file6, r32, expectBoth, outcome, assemble5, manifest, suiteFile, expectListed,
  QUANT6, CUBE_CODES, cubeBits, objectRecord, planesRecord, cubeGroup, cube6Records,
} from './files.mjs';

const [OBJT, PLNS, GRUP, COLR, META] = [1, 2, 3, 4, 5];
const QUANT = QUANT6;
const cubeRecords = cube6Records;
const cube = (h = {}, method = 0) => file6(header6({ ...QUANT, ...h }), { first: segment(cubeRecords(), method) });

/** A translation by (x, 0, 0) as version 4's coded transform: codes 1 0 0 2 / 0 1 0 0 / 0 0 1 0, then x as f32. @param {number} x */
function translation(x) {
  const codes = [1, 0, 0, 2, 0, 1, 0, 0, 0, 0, 1, 0];
  let v = 0;
  codes.forEach((c, i) => { v |= c << (2 * i); });
  return [v & 0xff, (v >> 8) & 0xff, (v >> 16) & 0xff, ...f32(x)];
}

/** Two objects (the second a child moved by 2 along x), each a cube, with colours and a keyword. */
function sceneRecords() {
  return [
    ...record(META, [...Buffer.from('author'), 0, ...Buffer.from('me')]),
    ...objectRecord('a'), ...planesRecord(), ...objectRecord('b', 1, translation(2)),
    ...cubeGroup(0), ...record(COLR, [0, 6, 255, 0, 0, 255]),
    ...cubeGroup(1), ...record(COLR, [1, 6, ...Array.from({ length: 6 }, (_, i) => [i, 2 * i, 3 * i, 255]).flat()]),
  ];
}

/** The conformance report, the same through both entries. @param {Uint8Array} bytes @returns {any} */
const bothJson = (bytes) => {
  const json = conformanceJson(readNode(bytes));
  assert.deepEqual(conformanceJson(readBrowser(bytes)), json, 'browser.mjs reads it alike');
  return json;
};

/** The error readNode throws. @param {Uint8Array} bytes @returns {PlnError} */
function errorOf(bytes) {
  try {
    readNode(bytes);
  } catch (err) {
    if (err instanceof PlnError) return err;
    throw err;
  }
  assert.fail('read');
}

test('r32: 0 takes one byte, 1, 0.5 and -1 two, NaN two, any f32 at most five; a tolerance of 12 mantissa bits three', () => {
  assert.deepEqual([0, 1, 0.5, -1, NaN].map((v) => r32(v).length), [1, 2, 2, 2, 2]);
  assert.deepEqual(r32(0), [0]);
  assert.ok(r32(Math.fround(Math.PI)).length <= 5);
  // 3e-5 rounded up to 12 explicit mantissa bits (its low 11 bits zero)
  const bits = new DataView(Float32Array.of(3e-5).buffer).getUint32(0, true);
  const up = new DataView(Uint32Array.of(((bits >>> 11) + 1) * 2048).buffer).getFloat32(0, true);
  assert.equal(r32(up).length, 3);
});

test('the cube: one segment in PHDR, no BODY chunk, 12 triangles of volume 1; every header field read', () => {
  const bytes = cube();
  assert.ok(bytes.length <= 72, `${bytes.length} bytes`);
  const file = readNode(bytes);
  assert.deepEqual(file.chunks.map((c) => c.type), ['PHDR', 'PEND']);
  assert.deepEqual(file.version, [6, 0]);
  const h = file.header;
  assert.deepEqual([h.coding, h.bits, h.h_range, h.lossy, h.bbox, h.counts], [2, [2, 2, 1], [0.5, 0.5], false, null, null]);
  assert.ok(Number.isNaN(h.tolerance) && Number.isNaN(h.error_bound));
  const json = bothJson(bytes);
  assert.deepEqual(json.objects, [{ name: '', parent: null, transform: null }]);
  assert.deepEqual(json.groups[0].refs, [0, 1, 2, 3, 4, 5]);
  const g = json.geometry.groups[0];
  assert.equal(g.triangles, 12);
  assert.ok(Math.abs(g.volume - 1) < 1e-12 && Math.abs(g.area - 6) < 1e-12);
  assert.deepEqual(json.geometry.world_bbox.map((/** @type {number[]} */ p) => p.map((v) => Math.round(v * 1e9) / 1e9 + 0)), [[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]]);
  assert.deepEqual(json.findings, []);
});

test('spec §5\'s example header (the unit cube [0, 1]³, widths 2, 2, 1, h range [0, 1], metres, tolerance 0) reads as it says', () => {
  const example = [0x06, 0x00, 0x09, 0x10, 0x01, 0x21, 0x00, 0x00, 0xfc, 0x03, 0x00, 0x00];
  assert.deepEqual(header6({ coding: 2, bits: [2, 2, 1], hRange: [0, 1], units: 1, tolerance: 0, errorBound: 0 }), example);
  const codes = [[0, 0, 1], [2, 0, 0], [1, 0, 1], [1, 2, 0], [1, 1, 1], [1, 3, 0]];
  const bits = [0, 0, 0, 0];
  codes.forEach(([n, p, h], i) => {
    const v = n | (p << 2) | (h << 4);
    for (let b = 0; b < 5; b++) if (v & (1 << b)) bits[(5 * i + b) >> 3] |= 1 << ((5 * i + b) & 7);
  });
  const bytes = file6(example, { first: segment([...objectRecord(), ...record(PLNS, [6, ...bits]), ...cubeGroup()]) });
  const file = readNode(bytes);
  assert.deepEqual([file.header.units, file.header.h_range, file.header.tolerance, file.header.error_bound], [1, [0, 1], 0, 0]);
  const g = bothJson(bytes).geometry;
  assert.deepEqual(g.world_bbox.map((/** @type {number[]} */ p) => p.map((v) => Math.round(v * 1e9) / 1e9 + 0)), [[0, 0, 0], [1, 1, 1]]);
  assert.ok(Math.abs(g.groups[0].volume - 1) < 1e-12);
});

test('header fields: flags, units and up axis, bbox, tolerance, error bound, counts, each an r32 or varint', () => {
  const bytes = file6(header6({
    ...QUANT, lossy: true, units: 0x13, bbox: [-0.5, -0.5, -0.5, 0.5, 0.5, 0.5], tolerance: 0.25, errorBound: 0.125, counts: [6, 1, 1],
  }), { first: segment(cubeRecords()) });
  const file = readNode(bytes);
  const h = file.header;
  assert.deepEqual([h.lossy, h.units, h.up_axis, h.bbox, h.tolerance, h.error_bound, h.counts],
    [true, 3, 'Y', [[-0.5, -0.5, -0.5], [0.5, 0.5, 0.5]], 0.25, 0.125, { planes: 6, objects: 1, groups: 1 }]);
  assert.equal(file.metadata.up_axis, 'Y');
  // codings 0 and 1 have no widths and no h range; a file without planes says coding 0
  const floats = file6(header6({ coding: 1 }), {
    first: segment([...objectRecord(), ...record(PLNS, [1, ...new Uint8Array(Float64Array.of(0, 0, 1).buffer)])]),
  });
  assert.deepEqual([readNode(floats).header.coding, readNode(floats).header.bits, [...readNode(floats).planes]], [1, [0, 0, 0], [0, 0, 1]]);
  // the coding is bits 3-4 of flags; bits 5-7 are ignored, and so is bit 15 of the widths
  const hdr = header6(QUANT);
  const loud = [...hdr];
  loud[3] |= 0xe0;
  loud[6] |= 0x80;
  assert.deepEqual(conformanceJson(readNode(file6(loud, { first: segment(cubeRecords()) }))).geometry, bothJson(cube()).geometry);
});

test('header_size: fields past the known ones are skipped (a newer minor\'s); too large or too small is BAD_PAYLOAD', () => {
  const later = file6(header6({ ...QUANT, later: [1, 2, 3] }), { first: segment(cubeRecords()) });
  assert.deepEqual(bothJson(later).geometry, bothJson(cube()).geometry);
  const fields = header6(QUANT).length - 3;
  // header_size past the payload's end: no segment, no PEND inside it
  expectBoth(file6(header6({ ...QUANT, size: fields + 40 }), { first: segment(cubeRecords()) }), 'BAD_PAYLOAD');
  expectBoth(file6(header6({ ...QUANT, size: fields + 40 })), 'BAD_PAYLOAD');
  // smaller than the fields the flags and coding call for: the header ends inside them
  for (const size of [0, 1, 2, fields - 1]) expectBoth(file6(header6({ ...QUANT, size }), { first: segment(cubeRecords()) }), 'BAD_PAYLOAD');
  expectBoth(file6(header6({ ...QUANT, counts: [6, 1, 1], size: fields + 2 }), { first: segment(cubeRecords()) }), 'BAD_PAYLOAD');
  // a PHDR of the version alone, or of an unfinished header_size
  expectBoth(file6([6, 0]), 'BAD_PAYLOAD');
  expectBoth(file6([6, 0, 0x80]), 'BAD_PAYLOAD');
});

test('r32 values: a varint that is not minimal, or of 2^32 or more, is BAD_PAYLOAD; values checked as in version 5', () => {
  const tail = header6({}); // flags, units, tolerance (NaN: 2 bytes), error bound (2 bytes)
  const raw = (/** @type {number[]} */ fields) => file6([6, 0, fields.length, ...fields]);
  assert.deepEqual(tail.slice(3), [0, 0, ...r32(NaN), ...r32(NaN)]);
  expectBoth(raw([0, 0, 0, 0]), 'ok');
  expectBoth(raw([0, 0, 0x80, 0x00, 0]), 'BAD_PAYLOAD');
  expectBoth(raw([0, 0, 0x80, 0x80, 0x80, 0x80, 0x10, 0]), 'BAD_PAYLOAD');
  expectBoth(raw([0, 0, 0xff, 0xff, 0xff, 0xff, 0x0f, 0]), 'ok'); // 2^32 - 1 reversed: a NaN
  // −1 as a tolerance, +∞ as an error bound, a bbox min above its max, h_min above h_max, units 8, up axis 3
  expectBoth(file6(header6({ tolerance: -1 })), 'BAD_HEADER_VALUE');
  expectBoth(file6(header6({ errorBound: Infinity })), 'BAD_HEADER_VALUE');
  expectBoth(file6(header6({ bbox: [1, 0, 0, 0, 1, 1] })), 'BAD_HEADER_VALUE');
  expectBoth(file6(header6({ ...QUANT, hRange: [1, 0] })), 'BAD_HEADER_VALUE');
  expectBoth(file6(header6({ units: 8 })), 'BAD_HEADER_VALUE');
  expectBoth(file6(header6({ units: 0x30 })), 'BAD_HEADER_VALUE');
  // widths are stored minus 1 in 5 bits: 32 reads
  expectBoth(file6(header6({ coding: 2, bits: [32, 32, 32], hRange: [0, 1] })), 'ok');
});

test('versions: 7 and up refused, 6.1 read with NEWER_MINOR_VERSION and its unknown group kinds skipped', () => {
  for (const major of [7, 255]) expectBoth(file6([major, 0, ...header6().slice(2)]), 'UNSUPPORTED_VERSION');
  const newer = file6(header6({ ...QUANT, minor: 1 }), {
    first: segment([...cubeRecords(), ...record(GRUP, [0, 14, ...common([0])])]),
  });
  const f = readNode(newer);
  assert.deepEqual([...f.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  assert.deepEqual(f.meshes.map((m) => m && m.indices.length / 3), [12, null]);
  expectBoth(file6(header6(QUANT), { first: segment([...cubeRecords(), ...record(GRUP, [0, 14, ...common([0])])]) }), 'UNKNOWN_GROUP_KIND');
});

test('a scene of two objects: names, parent, transform, colours (one for all, one per reference), a keyword', () => {
  const bytes = file6(header6({ ...QUANT, counts: [6, 2, 2] }), { first: segment(sceneRecords()) });
  const json = bothJson(bytes);
  assert.deepEqual(json.objects.map((/** @type {any} */ o) => [o.name, o.parent]), [['a', null], ['b', 0]]);
  assert.deepEqual(json.objects[1].transform, [1, 0, 0, 2, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
  assert.deepEqual(json.groups.map((/** @type {any} */ g) => [g.index, g.object]), [[0, 0], [1, 1]]);
  assert.deepEqual(json.colours[0], { group: 0, rgba: Array(6).fill([255, 0, 0, 255]) });
  assert.deepEqual(json.colours[1].rgba[5], [5, 10, 15, 255]);
  assert.deepEqual({ ...json.metadata }, { author: 'me' });
  assert.deepEqual(json.geometry.world_bbox[1].map((/** @type {number} */ v) => Math.round(v * 1e9) / 1e9 + 0), [2.5, 0.5, 0.5]);
  const mesh = readNode(bytes).mesh();
  assert.equal(mesh.indices.length / 3, 24);
});

test('BODY chunks: segments stored, zlib, Brotli; the PHDR segment and BODY segments read as one sequence of records', () => {
  const records = sceneRecords();
  const want = bothJson(file6(header6(QUANT), { first: segment(records) })).geometry;
  // at record boundaries: the keyword and object a (11 + 6 bytes), the planes (7), the rest
  const at = [0, 17, 24, records.length];
  const parts = [records.slice(at[0], at[1]), records.slice(at[1], at[2]), records.slice(at[2], at[3])];
  for (const method of [0, 1, 2]) {
    const inPhdr = file6(header6(QUANT), {
      first: segment(parts[0], method),
      chunks: parts.slice(1).map((p) => ({ type: 'BODY', payload: segment(p, method) })),
    });
    assert.deepEqual(bothJson(inPhdr).geometry, want, `method ${method}`);
    const allBody = file6(header6(QUANT), { chunks: parts.map((p) => ({ type: 'BODY', payload: segment(p, method) })) });
    assert.deepEqual(readNode(allBody).chunks.map((c) => c.type), ['PHDR', 'BODY', 'BODY', 'BODY', 'PEND']);
    assert.deepEqual(bothJson(allBody).geometry, want, `method ${method}, no segment in PHDR`);
  }
  // an empty segment (raw size 0) holds no record; an unknown ancillary chunk between BODY chunks is skipped
  const spaced = file6(header6(QUANT), {
    chunks: [{ type: 'BODY', payload: segment([]) }, { type: 'BODY', payload: segment(cubeRecords()) }, { type: 'zZZZ', payload: [1] }],
  });
  assert.deepEqual([...readNode(spaced).findings], ['UNKNOWN_ANCILLARY_CHUNK']);
});

test('one segment at a time: each is held to the payload limit on its own, and is decompressed as its chunk is read', () => {
  const parts = [cubeRecords().slice(0, 12), cubeRecords().slice(12)]; // the object and planes records, the group
  const bytes = file6(header6(QUANT), { chunks: parts.map((p) => ({ type: 'BODY', payload: segment(p, 1) })) });
  const largest = Math.max(...parts.map((p) => p.length));
  assert.equal(outcome(bytes, readNode, { limits: { rawSize: largest } }), 'ok');
  assert.equal(outcome(bytes, readNode, { limits: { rawSize: largest - 1 } }), 'LIMIT_EXCEEDED');
  /** @type {number[]} */
  const sizes = [];
  const inflate = (/** @type {Uint8Array} */ s, /** @type {number} */ max) => {
    const out = zlib.inflateSync(s, { maxOutputLength: max });
    sizes.push(out.length);
    return new Uint8Array(out);
  };
  readNode(bytes, { inflate });
  assert.deepEqual(sizes, parts.map((p) => p.length));
  // a segment damaged after the first is reported at its own chunk, the first having been read
  const bad = file6(header6(QUANT), { chunks: [{ type: 'BODY', payload: segment(parts[0], 1) }, { type: 'BODY', payload: [1, 20, 1, 2, 3] }] });
  const err = errorOf(bad);
  assert.deepEqual([err.code, err.chunk, err.offset], ['BAD_COMPRESSION', 'BODY', readNode(bytes).chunks[2].offset]);
});

test('segments: §6 checks of method, limits, sizes; an empty BODY payload is BAD_PAYLOAD', () => {
  const raw = cubeRecords();
  const body = (/** @type {number[]} */ payload) => file6(header6(QUANT), { chunks: [{ type: 'BODY', payload }] });
  const phdr = (/** @type {number[]} */ seg) => file6(header6(QUANT), { first: seg });
  for (const build of [body, phdr]) {
    expectBoth(build([3, ...varint(raw.length), ...raw]), 'BAD_COMPRESSION');
    expectBoth(build([0, ...varint(raw.length + 1), ...raw]), 'SIZE_MISMATCH');
    const z = [...zlib.deflateSync(Uint8Array.from(raw))];
    expectBoth(build([1, ...varint(raw.length - 1), ...z]), 'SIZE_MISMATCH');
    expectBoth(build([1, ...varint(raw.length), ...z.slice(0, -3)]), 'SIZE_MISMATCH');
    expectBoth(build([1, ...varint(raw.length), 0x79, 0x9c, 0xff, 0xff]), 'BAD_COMPRESSION'); // compression method 9
    expectBoth(build([1, ...varint(2000), 1]), 'LIMIT_EXCEEDED'); // above 1100 times its stored size
    expectBoth(build([0, 0x80]), 'BAD_PAYLOAD'); // ends inside raw_size
  }
  expectBoth(body([]), 'BAD_PAYLOAD');
  assert.equal(outcome(body(segment(raw)), readNode, { limits: { rawSize: raw.length - 1 } }), 'LIMIT_EXCEEDED');
});

test('records: a length past the segment, a segment ending inside a record head, BAD_PAYLOAD naming chunk and record', () => {
  const raw = cubeRecords();
  const cut = file6(header6(QUANT), { chunks: [{ type: 'BODY', payload: segment(raw.slice(0, -1)) }] });
  const err = errorOf(cut);
  assert.deepEqual([err.code, err.chunk, err.offset], ['BAD_PAYLOAD', 'BODY', 8 + 12 + header6(QUANT).length]);
  assert.match(err.message, /record of tag 3 at byte 12 /);
  assert.deepEqual(err.record, { tag: GRUP, offset: 12 });
  expectBoth(file6(header6(QUANT), { first: segment([...raw, GRUP]) }), 'BAD_PAYLOAD');
  expectBoth(file6(header6(QUANT), { first: segment([...raw, GRUP, 0x80]) }), 'BAD_PAYLOAD');
  // a record never spans two segments: the rest in the next segment does not help
  expectBoth(file6(header6(QUANT), { first: segment(raw.slice(0, -1)), chunks: [{ type: 'BODY', payload: segment(raw.slice(-1)) }] }), 'BAD_PAYLOAD');
  // a length that is not a minimal varint32
  expectBoth(file6(header6(QUANT), { first: segment([...raw, 128, 0x80, 0x00]) }), 'BAD_PAYLOAD');
});

test('record tags: 1-5 known, 128-255 skipped as ancillary, 0 and 6-127 unknown critical', () => {
  for (const tag of [128, 200, 255]) {
    const f = readNode(file6(header6(QUANT), { first: segment([...record(tag, [9, 9, 9]), ...cubeRecords(), ...record(tag, [])]) }));
    assert.deepEqual([...f.findings], ['UNKNOWN_ANCILLARY_CHUNK'], `tag ${tag}`);
    // the raw bytes per record type, tag and length included: the skipped ones under their tag
    assert.deepEqual(f.container.records, [
      { type: `tag ${tag}`, records: 2, bytes: 5 + 2 }, { type: 'OBJT', records: 1, bytes: 5 },
      { type: 'PLNS', records: 1, bytes: 7 }, { type: 'GRUP', records: 1, bytes: 12 },
    ]);
    assert.equal(f.meshes[0]?.indices.length, 36);
  }
  for (const tag of [0, 6, 7, 64, 127]) {
    expectBoth(file6(header6(QUANT), { first: segment([...cubeRecords(), ...record(tag, [])]) }), 'UNKNOWN_CRITICAL_CHUNK');
  }
});

test('chunks: OBJT, PLNS, GRUP, cOLR, mETA are CHUNK_ORDER in version 6; BODY is unknown critical before it; BODY after iNDX', () => {
  const v5obj = { type: 'OBJT', payload: [0, 0, 0, 0] };
  for (const type of ['OBJT', 'PLNS', 'GRUP', 'cOLR', 'mETA']) {
    expectBoth(file6(header6(QUANT), { first: segment(cubeRecords()), chunks: [{ type, payload: v5obj.payload }] }), 'CHUNK_ORDER');
  }
  const v5 = assemble5([{ type: 'PHDR', payload: [5, 0, 0, 0, 0, 0, 0, 0, ...f32(NaN), ...f32(NaN)] },
    { type: 'BODY', payload: segment([]) }, { type: 'PEND', payload: [] }]);
  expectBoth(v5, 'UNKNOWN_CRITICAL_CHUNK');
  expectBoth(file6(header6(QUANT), { first: segment(cubeRecords()), chunks: [{ type: 'PLNs', payload: [] }] }), 'UNKNOWN_CRITICAL_CHUNK');
  expectBoth(file6(header6(QUANT), { first: segment(cubeRecords()), chunks: [{ type: 'iNDX', payload: index6([[8, 0, OBJT, 0], [8, 5, PLNS, 0], [8, 12, GRUP, 0]]) }, { type: 'BODY', payload: segment([]) }] }), 'CHUNK_ORDER');
});

test('record payloads: version 6\'s differences from the chunks, with their checks', () => {
  const file = (/** @type {number[]} */ raw, h = {}) => file6(header6({ ...QUANT, ...h }), { first: segment(raw) });
  const obj = objectRecord();
  // planes: count and raw data only; a size that does not fit the count is SIZE_MISMATCH; the plane limit
  expectBoth(file([...obj, ...record(PLNS, [6, ...cubeBits(), 0]), ...cubeGroup()]), 'SIZE_MISMATCH');
  expectBoth(file([...obj, ...record(PLNS, [7, ...cubeBits()])]), 'SIZE_MISMATCH');
  expectBoth(file([...obj, ...record(PLNS, [])]), 'BAD_PAYLOAD');
  assert.equal(outcome(file(cubeRecords()), readNode, { limits: { planes: 5 } }), 'LIMIT_EXCEEDED');
  // two planes records: the table is their concatenation, no first index to check
  const twice = file([...obj, ...record(PLNS, [3, ...threePlanes(0)]), ...record(PLNS, [3, ...threePlanes(3)]), ...cubeGroup()]);
  assert.equal(readNode(twice).meshes[0]?.indices.length, 36);
  // the object: no index; a parent that is not earlier; name not UTF-8; a later field ignored
  expectBoth(file([...record(OBJT, [1, 0, 0])]), 'BAD_OBJECT');
  expectBoth(file([...record(OBJT, [0, 0, 1, 0xff])]), 'BAD_OBJECT');
  expectBoth(file([...record(OBJT, [0, 0, 0, 7, 7]), ...planesRecord(), ...cubeGroup()]), 'ok');
  expectBoth(file([...record(OBJT, [0, 0])]), 'BAD_PAYLOAD');
  assert.equal(outcome(file([...obj, ...obj]), readNode, { limits: { objects: 1 } }), 'LIMIT_EXCEEDED');
  // the group: object, kind, body; no index, compression or raw size
  expectBoth(file([...obj, ...planesRecord(), ...cubeGroup(1)]), 'BAD_OBJECT_REFERENCE');
  expectBoth(file([...obj, ...planesRecord(), ...record(GRUP, [0, 0, ...common([0, 1, 2, 3, 4, 6])])]), 'BAD_PLANE_REFERENCE');
  expectBoth(file([...obj, ...planesRecord(), ...record(GRUP, [0, 0, ...common([0, 1, 2, 3, 4, 5]), 0])]), 'BAD_PAYLOAD');
  expectBoth(file([...obj, ...planesRecord(), ...record(GRUP, [0])]), 'BAD_PAYLOAD');
  expectBoth(file([...obj, ...planesRecord(), ...record(GRUP, [0, 0, 0])]), 'BAD_GROUP_STRUCTURE');
  // a copy (kind 11) of the cube, in a second object
  const copy = file([...cubeRecords(), ...objectRecord('c', 1, translation(3)), ...record(GRUP, [1, 11, ...common([0, 1, 2, 3, 4, 5]), 0])]);
  const cj = bothJson(copy);
  assert.deepEqual([cj.groups[1].source, cj.geometry.groups[1].triangles], [0, 12]);
  // colours: group and count are varint32s; 4 bytes after them one colour for all
  const colr = (/** @type {number[]} */ p) => file([...cubeRecords(), ...record(COLR, p)]);
  expectBoth(colr([0, 6, 1, 2, 3, 4]), 'ok');
  expectBoth(colr([0, 6, ...Array(24).fill(1)]), 'ok');
  expectBoth(colr([1, 6, 1, 2, 3, 4]), 'BAD_COLOURS');
  expectBoth(colr([0, 5, 1, 2, 3, 4]), 'BAD_COLOURS');
  expectBoth(colr([0, 6, ...Array(25).fill(1)]), 'BAD_COLOURS');
  expectBoth(colr([0, 6, ...Array(23).fill(1)]), 'BAD_PAYLOAD');
  expectBoth(colr([0]), 'BAD_PAYLOAD');
  // colours before their group; metadata after an object, or up_axis as a keyword
  expectBoth(file([...obj, ...record(COLR, [0, 6, 1, 2, 3, 4]), ...planesRecord(), ...cubeGroup()]), 'BAD_COLOURS');
  expectBoth(file([...obj, ...record(META, [0x61, 0, 0x62])]), 'BAD_METADATA');
  expectBoth(file([...record(META, [...Buffer.from('up_axis'), 0, 0x59])]), 'BAD_METADATA');
  expectBoth(file([...record(META, [0x61, 0, 0x62]), ...cubeRecords()]), 'ok');
});

/** Three of the cube's planes (widths 2/2/1) from `from` on, in 15 bits. @param {number} from */
function threePlanes(from) {
  const out = [0, 0];
  CUBE_CODES.slice(from, from + 3).forEach(([n, p, h], i) => {
    const v = n | (p << 2) | (h << 4);
    for (let b = 0; b < 5; b++) if (v & (1 << b)) out[(5 * i + b) >> 3] |= 1 << ((5 * i + b) & 7);
  });
  return out;
}

test('counts: the header\'s plane, object and group counts are checked against the records at PEND', () => {
  expectBoth(cube({ counts: [6, 1, 1] }), 'ok');
  for (const counts of [[5, 1, 1], [6, 2, 1], [6, 1, 0]]) expectBoth(cube({ counts }), 'COUNT_MISMATCH');
});

/**
 * A version 6 iNDX payload: count, then per entry chunk offset (as a difference from the entry
 * before), raw offset, tag, ordinal. @param {number[][]} entries [chunk offset, raw offset, tag, ordinal]
 */
function index6(entries) {
  let last = 0;
  return [...varint(entries.length), ...entries.flatMap(([at, raw, tag, ordinal]) => {
    const d = at - last;
    last = at;
    return [...varint(d), ...varint(raw), tag, ...varint(ordinal)];
  })];
}

/** The cube with an index (and PEND's offset of it, where `pointed`). @param {number[][]} entries */
function indexed(entries, pointed = true) {
  const plain = cube();
  const phdrSize = readNode(plain).chunks[0].size;
  const at = 8 + phdrSize;
  const payload = index6(entries);
  const end = pointed ? [...new Uint8Array(BigUint64Array.of(BigInt(at)).buffer)] : [];
  return file6(header6(QUANT), { first: segment(cubeRecords()), chunks: [{ type: 'iNDX', payload }], end });
}

test('the index of version 6: chunk offset, raw offset, tag, ordinal per object, planes and group record', () => {
  const good = [[8, 0, OBJT, 0], [8, 5, PLNS, 0], [8, 12, GRUP, 0]];
  expectBoth(indexed(good), 'ok');
  expectBoth(indexed(good, false), 'ok');
  // across segments: the BODY chunk's offset, the record's place in its raw bytes
  const parts = [cubeRecords().slice(0, 5), cubeRecords().slice(5)];
  const noIndex = file6(header6(QUANT), { first: segment(parts[0]), chunks: [{ type: 'BODY', payload: segment(parts[1], 1) }] });
  const body = readNode(noIndex).chunks[1].offset;
  const two = file6(header6(QUANT), {
    first: segment(parts[0]), chunks: [{ type: 'BODY', payload: segment(parts[1], 1) }, { type: 'iNDX', payload: index6([[8, 0, OBJT, 0], [body, 0, PLNS, 0], [body, 7, GRUP, 0]]) }],
  });
  expectBoth(two, 'ok');
  for (const entries of [
    good.slice(0, 2), [...good, [8, 12, GRUP, 0]], [good[1], good[0], good[2]],
    [[8, 0, OBJT, 1], good[1], good[2]], [[8, 1, OBJT, 0], good[1], good[2]], [good[0], [9, 5, PLNS, 0], [9, 12, GRUP, 0]],
    [good[0], good[1], [8, 12, 4, 0]], [[7, 0, OBJT, 0], good[1], good[2]], [good[0], good[1], [500, 12, GRUP, 0]],
  ]) expectBoth(indexed(entries), 'BAD_INDEX', JSON.stringify(entries));
  // bytes after the entries; a payload that ends inside them
  const payload = index6(good);
  const withIndex = (/** @type {number[]} */ p) => file6(header6(QUANT), { first: segment(cubeRecords()), chunks: [{ type: 'iNDX', payload: p }] });
  expectBoth(withIndex([...payload, 0]), 'BAD_INDEX');
  expectBoth(withIndex(payload.slice(0, -1)), 'BAD_PAYLOAD');
  expectBoth(withIndex([0x80]), 'BAD_PAYLOAD');
  expectBoth(withIndex([...varint(2 ** 40)]), 'BAD_PAYLOAD');
  // PEND's offset of it as in version 5
  const wrongEnd = file6(header6(QUANT), { first: segment(cubeRecords()), chunks: [{ type: 'iNDX', payload }], end: [...new Uint8Array(8)] });
  expectBoth(wrongEnd, 'BAD_INDEX');
});

test('framing as version 5: varint chunk lengths after PHDR, a CRC per chunk, PEND last, nothing after it', () => {
  const bytes = cube();
  const broken = bytes.slice();
  broken[20] ^= 1;
  expectBoth(broken, 'CRC_MISMATCH');
  expectBoth(Uint8Array.from([...bytes, 0]), 'TRAILING_DATA');
  expectBoth(bytes.subarray(0, bytes.length - 9), 'TRUNCATED');
  assert.equal(readNode(bytes).chunks.at(-1)?.size, 9);
});

{
  const cases = manifest().filter(([file]) => /_v6_0\.pln$|\/xv6_/.test(file));
  test('the 6.0 conformance cases through both entries (node.mjs and browser.mjs)', { skip: cases.length === 0 && 'no 6.0 case in this suite' }, () => {
    for (const [file, expected] of cases) expectListed(suiteFile(file), expected, file);
  });
}
