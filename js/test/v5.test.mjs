// Version 5.0 (spec §4.1, §5, §9.2, §9.10, §10.1, §10.3, A.5) on files made here from the 5.0 golden
// files, for the points those files do not decide: lengths of three and five varint bytes, the
// framing order at the edges of §4.1 step 3, the header's ignored bits and later fields, groups
// without references where the goldens have none (a copy of such a shell, a kind of a newer minor,
// kinds 0-5), their colours, and the header's up axis in readPln's metadata and the three.js
// loader; every 5.0 conformance case through both entries (node.mjs and browser.mjs).
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readPln as readNode } from '../src/node.mjs';
import { PLNLoader } from '../three/PLNLoader.mjs';
import { Cursor } from '../src/varint.mjs';
import { golden, manifest, suiteFile, varint, assemble4, assemble5 as assemble, outcome, expectBoth, expectListed } from './files.mjs';

/** @typedef {{type: string, payload: Uint8Array, length?: number[]}} Chunk `length`: the length's bytes as stored, if not the minimal varint */

/**
 * The chunks of a version 5 file, by §4.1 alone: PHDR's length a u32, every later one a varint.
 * @param {Uint8Array} bytes @returns {Chunk[]}
 */
function chunksOf(bytes) {
  const out = [];
  for (let pos = 8; pos < bytes.length;) {
    let length;
    let head;
    if (pos === 8) {
      length = new DataView(bytes.buffer, bytes.byteOffset).getUint32(pos + 4, true);
      head = 8;
    } else {
      const c = new Cursor(bytes.subarray(pos + 4));
      length = c.varint();
      head = 4 + c.pos;
    }
    out.push({ type: String.fromCharCode(...bytes.subarray(pos, pos + 4)), payload: bytes.slice(pos + head, pos + head + length) });
    pos += head + length + 4;
  }
  return out;
}

/** The PHDR payload of `chunks` with its fixed part's bytes changed. @param {Chunk[]} chunks @param {Record<number, number>} at */
function withHeader(chunks, at, tail = /** @type {number[]} */ ([])) {
  const p = Uint8Array.from([...chunks[0].payload, ...tail]);
  for (const [i, v] of Object.entries(at)) p[Number(i)] = v;
  return [{ type: 'PHDR', payload: p }, ...chunks.slice(1)];
}

/** Without the header's counts (bit 1 of the u8 flags), so that chunks may be added. @param {Chunk[]} chunks */
function uncounted(chunks) {
  const p = chunks[0].payload;
  assert.equal(p[2] & 2, 2, 'COUNTS_KNOWN');
  // the counts are the last three varints: planes, objects, groups (§5); drop them with the flag
  const c = new Cursor(p.subarray(p.length - 3));
  c.varint(); c.varint(); c.varint();
  assert.equal(c.left, 0, 'three one-byte counts');
  const q = p.slice(0, p.length - 3);
  q[2] &= ~2;
  return [{ type: 'PHDR', payload: q }, ...chunks.slice(1)];
}

/** A GRUP payload of method 0. @param {number} index @param {number} object @param {number} kind @param {number[]} body */
const grup = (index, object, kind, body) => Uint8Array.from([...varint(index), ...varint(object), kind, 0, ...varint(body.length), ...body]);

/** The raw body of a method-0 GRUP payload and its kind. @param {Uint8Array} p */
function bodyOf(p) {
  const c = new Cursor(p);
  c.varint(); c.varint();
  const kind = c.u8();
  assert.equal(c.u8(), 0, 'method 0');
  c.varint();
  return { kind, body: [...c.take(c.left)] };
}

const planeless = chunksOf(golden('walk_planeless_v5_0.pln'));

test('the chunk walker here reads the 5.0 goldens as readPln does, and assemble gives them back byte for byte', () => {
  for (const name of ['walk_planeless_v5_0.pln', 'scene_up_axis_v5_0.pln', 'shells_v5_0.pln']) {
    const bytes = golden(name);
    assert.deepEqual(assemble(chunksOf(bytes)), bytes, name);
    const file = readNode(bytes);
    // a chunk's size: 8 + 4 for PHDR, type + varint + CRC after it; together the file after the signature
    assert.equal(file.chunks.reduce((s, c) => s + c.size, 8), bytes.length, name);
    assert.deepEqual(file.chunks.slice(1).map((c) => c.size), chunksOf(bytes).slice(1).map((c) => 8 + varint(c.payload.length).length + c.payload.length));
  }
});

test('§4.1: lengths of one, two, three varint bytes at their bounds; PEND 9 bytes', () => {
  // an ancillary chunk unknown here ("zFIL", §4.2) of each length, after PHDR: ignored, counted by size
  const [hdr, ...rest] = planeless;
  for (const [n, bytes] of [[0, 1], [127, 1], [128, 2], [16383, 2], [16384, 3], [70000, 3]]) {
    const file = readNode(assemble([hdr, { type: 'zFIL', payload: new Uint8Array(n).fill(7) }, ...rest]));
    const z = /** @type {{size: number, length: number}} */ (file.chunks.find((c) => c.type === 'zFIL'));
    assert.deepEqual([z.length, z.size], [n, 4 + bytes + n + 4], `length ${n}`);
    assert.ok(file.findings.has('UNKNOWN_ANCILLARY_CHUNK'));
    assert.equal(file.meshes[0]?.indices.length, readNode(golden('walk_planeless_v5_0.pln')).meshes[0]?.indices.length);
  }
  assert.equal(readNode(golden('walk_planeless_v5_0.pln')).chunks.at(-1)?.size, 9);
  assert.equal(readNode(golden('scene_up_axis_v5_0.pln')).chunks.at(-1)?.size, 17);
});

test('§4.1 framing order at the varint length: TRUNCATED, BAD_CHUNK_TYPE, BAD_CHUNK_LENGTH, CHUNK_TOO_LONG, LIMIT_EXCEEDED', () => {
  const [hdr, obj] = planeless;
  const head = assemble([hdr]);
  const after = (/** @type {number[]} */ tail) => Uint8Array.from([...head, ...tail]);
  const OBJT = [...'OBJT'].map((c) => c.charCodeAt(0));
  // the input ends inside the type, then inside the varint (after the type is checked)
  expectBoth(after(OBJT.slice(0, 3)), 'TRUNCATED');
  expectBoth(after([0x4f, 0x42, 0x4a, 0x31, 0x88]), 'BAD_CHUNK_TYPE'); // "OBJ1" and a varint cut short: the type first
  expectBoth(after([...OBJT, 0x88, 0x80]), 'TRUNCATED');
  expectBoth(after([...OBJT, 0x88, 0x80, 0x80, 0x80]), 'TRUNCATED');
  // a fifth byte with bit 7 set is too long even where the input ends right after it
  expectBoth(after([...OBJT, 0x88, 0x80, 0x80, 0x80, 0x80]), 'CHUNK_TOO_LONG');
  // not minimal at three and five bytes (a 0x00 last byte), whatever follows
  expectBoth(after([...OBJT, 0x8a, 0x80, 0x00]), 'BAD_CHUNK_LENGTH');
  expectBoth(after([...OBJT, 0x80, 0x80, 0x80, 0x80, 0x00]), 'BAD_CHUNK_LENGTH');
  expectBoth(assemble([hdr, { ...obj, length: [obj.payload.length | 0x80, 0x80, 0x00] }]), 'BAD_CHUNK_LENGTH');
  // 2^31 - 1 is a length (the reader's limit or the input decides), 2^31 and 2^32 - 1 are not
  expectBoth(after([...OBJT, 0xff, 0xff, 0xff, 0xff, 0x07]), 'LIMIT_EXCEEDED');
  assert.equal(outcome(after([...OBJT, 0xff, 0xff, 0xff, 0xff, 0x07]), (b) => readNode(b, { limits: { chunkLength: 2 ** 31 } })), 'TRUNCATED');
  assert.equal(outcome(after([...OBJT, 0x80, 0x80, 0x80, 0x80, 0x08]), (b) => readNode(b, { limits: { chunkLength: 2 ** 32 } })), 'CHUNK_TOO_LONG');
  expectBoth(after([...OBJT, 0xff, 0xff, 0xff, 0xff, 0x0f]), 'CHUNK_TOO_LONG');
  // PHDR keeps its u32 in version 5; a minimal varint of a length that fits one byte reads
  expectBoth(assemble(planeless), 'ok');
});

test('§4.1: a second PHDR in a version 5 file is a chunk after PHDR (varint length): DUPLICATE_HEADER', () => {
  const [hdr, ...rest] = planeless;
  expectBoth(assemble([hdr, hdr, ...rest]), 'DUPLICATE_HEADER');
});

test('§5: version 5 header: flags a u8, bits 3-7 ignored; units bits 6-7 ignored; later fields ignored; up axis', () => {
  const base = readNode(assemble(planeless));
  assert.deepEqual([base.header.units, base.header.up_axis, base.header.coding], [1, 'Z', 0]);
  assert.equal(planeless[0].payload[7], 0x21, 'units byte (offset 7): metre, Z up');
  // flags bits 3-7 and units bits 6-7 set: the same file
  const noisy = readNode(assemble(withHeader(planeless, { 2: planeless[0].payload[2] | 0xf8, 7: 0xe1 }, [1, 2, 3])));
  assert.deepEqual(noisy.header, base.header);
  /** @type {[number, number, string | null][]} the units byte, its unit and up axis */
  const bytes = [[0x01, 1, null], [0x11, 1, 'Y'], [0x27, 7, 'Z'], [0x00, 0, null], [0xd3, 3, 'Y']];
  for (const [byte, unit, up] of bytes) {
    const f = readNode(assemble(withHeader(planeless, { 7: byte })));
    assert.deepEqual([f.header.units, f.header.up_axis, f.metadata.up_axis ?? null], [unit, up, up], `units byte ${byte}`);
  }
  expectBoth(assemble(withHeader(planeless, { 7: 0x31 })), 'BAD_HEADER_VALUE'); // up axis 3
  expectBoth(assemble(withHeader(planeless, { 7: 0x28 })), 'BAD_HEADER_VALUE'); // unit 8
  expectBoth(assemble(withHeader(planeless, { 7: 0x0f })), 'BAD_HEADER_VALUE'); // unit 15
  // the fixed part is 8 bytes: coding at offset 3
  expectBoth(assemble(withHeader(planeless, { 3: 4 })), 'UNSUPPORTED_CODING');
  expectBoth(assemble([{ type: 'PHDR', payload: planeless[0].payload.slice(0, 8) }, ...planeless.slice(1)]), 'BAD_PAYLOAD'); // ends inside bbox
  // a version 5 file says its up axis in the header only (§10.3); another keyword is welcome
  const meta = (/** @type {string} */ k, /** @type {string} */ v) => ({ type: 'mETA', payload: new TextEncoder().encode(`${k}\0${v}`) });
  expectBoth(assemble([planeless[0], meta('up_axis', 'Y'), ...planeless.slice(1)]), 'BAD_METADATA');
  expectBoth(assemble([...withHeader(planeless, { 7: 0x01 }).slice(0, 1), meta('up_axis', 'Z'), ...planeless.slice(1)]), 'BAD_METADATA');
  const other = readNode(assemble([planeless[0], meta('author', 'x'), ...planeless.slice(1)]));
  assert.deepEqual({ ...other.metadata }, { author: 'x', up_axis: 'Z' });
  assert.deepEqual({ ...other.container.metadata }, { author: 'x' }, 'the container keeps mETA apart');
});

test('three.js loader: a version 5 header\'s up axis is userData.upAxis, as a mETA up_axis is before version 5', () => {
  assert.equal(new PLNLoader().parse(golden('walk_planeless_v5_0.pln')).userData.upAxis, 'Z');
  assert.equal(new PLNLoader().parse(golden('scene_up_axis_v5_0.pln')).userData.upAxis, 'Y');
  assert.equal(new PLNLoader().parse(golden('shells_v5_0.pln')).userData.upAxis, null);
  assert.equal(new PLNLoader().parse(golden('cube_meta_up_z.pln')).userData.upAxis, 'Z');
});

test('§9.2, §9.15, §10.1: a copy without references of a shell without references; one colour for all or none', () => {
  const chunks = uncounted(planeless);
  const g = /** @type {Chunk} */ (chunks.find((c) => c.type === 'GRUP'));
  const { kind, body } = bodyOf(g.payload);
  assert.deepEqual([kind, body[0]], [9, 0], 'a kind 9 shell walk with m = 0');
  const end = /** @type {Chunk} */ (chunks.at(-1));
  const objt2 = { type: 'OBJT', payload: Uint8Array.from([1, 0, 0, 1, 0x63]) }; // object 1 "c", a root, no transform
  const copy = { type: 'GRUP', payload: grup(1, 1, 11, [0, 0]) }; // m = 0, source 0
  const file = readNode(assemble([...chunks.slice(0, -1), objt2, copy, end]));
  const a = /** @type {NonNullable<typeof file.meshes[0]>} */ (file.meshes[0]);
  const b = /** @type {NonNullable<typeof file.meshes[0]>} */ (file.meshes[1]);
  assert.ok(a && b);
  assert.equal(b.source, 0);
  assert.deepEqual([...b.indices], [...a.indices]);
  assert.equal(b.faceColors, null);
  assert.deepEqual([...file.container.groups[1].refs], []);
  // a cOLR of count 0 without a colour (8 bytes): BAD_COLOURS; with one (12 bytes): every triangle takes it
  for (const group of [0, 1]) {
    const none = { type: 'cOLR', payload: Uint8Array.from([group, 0, 0, 0, 0, 0, 0, 0]) };
    expectBoth(assemble([...chunks.slice(0, -1), objt2, copy, none, end]), 'BAD_COLOURS');
    const one = { type: 'cOLR', payload: Uint8Array.from([group, 0, 0, 0, 0, 0, 0, 0, 1, 2, 3, 4]) };
    const coloured = readNode(assemble([...chunks.slice(0, -1), objt2, copy, one, end]));
    const mesh = /** @type {NonNullable<typeof coloured.meshes[0]>} */ (coloured.meshes[group]);
    assert.deepEqual([...(mesh.faceColors ?? []).subarray(0, 8)], [1, 2, 3, 4, 1, 2, 3, 4]);
  }
  // a copy with a reference of a source with none: BAD_PLANE_REFERENCE here (no planes)
  expectBoth(assemble([...chunks.slice(0, -1), objt2, { type: 'GRUP', payload: grup(1, 1, 11, [1, 0, 0, 0]) }, end]), 'BAD_PLANE_REFERENCE');
});

test('§9.2: m = 0 in kinds 0-5 is BAD_GROUP_STRUCTURE; a kind of a newer minor decides for itself; version 4 refuses it', () => {
  const chunks = uncounted(planeless);
  const at = chunks.findIndex((c) => c.type === 'GRUP');
  const withGroup = (/** @type {number} */ kind, /** @type {number[]} */ body, minor = 0) => {
    const c = withHeader(chunks, { 1: minor });
    c[at] = { type: 'GRUP', payload: grup(0, 0, kind, body) };
    return assemble(c);
  };
  for (const kind of [0, 1, 2, 3, 4, 5]) expectBoth(withGroup(kind, [0, 1, 2, 3]), 'BAD_GROUP_STRUCTURE');
  // kind 12 is 5.1's (§9.3): unknown in 5.0; kind 13 (5.2's) unknown in 5.1; kind 14 unknown in 5.2 and skipped in 5.3
  expectBoth(withGroup(12, [0, 1, 2, 3]), 'UNKNOWN_GROUP_KIND');
  expectBoth(withGroup(13, [0, 1, 2, 3], 1), 'UNKNOWN_GROUP_KIND');
  expectBoth(withGroup(14, [0, 1, 2, 3], 2), 'UNKNOWN_GROUP_KIND');
  const skipped = readNode(withGroup(14, [0, 1, 2, 3], 3));
  assert.deepEqual([...skipped.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  assert.equal(skipped.meshes[0], null);
  // the golden shell walk's body in a 4.2 file: m = 0 is BAD_GROUP_STRUCTURE in every kind of major 4 (A.5)
  const { body } = bodyOf(/** @type {Chunk} */ (chunks[at]).payload);
  // a 4.2 header: version, u16 flags 0, coding 0, widths, units, tolerance and error bound NaN
  const nan = [0, 0, 0xc0, 0x7f];
  const hdr4 = Uint8Array.from([4, 2, 0, 0, 0, 0, 0, 0, 1, ...nan, ...nan]);
  const file4 = assemble4([{ type: 'PHDR', payload: hdr4 }, { type: 'OBJT', payload: chunks[1].payload },
    { type: 'GRUP', payload: grup(0, 0, 9, body) }, { type: 'PEND', payload: new Uint8Array(0) }]);
  expectBoth(file4, 'BAD_GROUP_STRUCTURE');
  expectBoth(withGroup(9, body), 'ok');
});

test('§9.10: a version 5 grid is 16 bytes of f32; the same shell with an f64 grid is not read as one', () => {
  const file = readNode(golden('shells_v5_0.pln'));
  for (const g of file.container.groups) {
    const s = g.data;
    // every grid value an f32
    for (const v of [...s.origin, s.step]) assert.equal(Math.fround(v), v);
  }
  const planelessFile = readNode(assemble(planeless));
  assert.deepEqual([planelessFile.container.groups[0].data.origin, planelessFile.container.groups[0].data.step], [[0, 0, 0], 0.25]);
});

test('the 5.0 conformance cases through both entries', () => {
  const cases = manifest().filter(([file]) => /_v5_0\.pln$|\/xv50_/.test(file));
  assert.ok(cases.length >= 13, `${cases.length} cases`);
  for (const [file, expected] of cases) expectListed(suiteFile(file), expected, file);
});
