// Version 4.0 (spec §5, §6, §8, §10.1, Appendix A) on files made here: every 3.x golden file
// rewritten as 4.0 (Brotli payloads, transforms coded entry by entry, one colour for a group)
// reads as the original does; Brotli's errors (§6 steps 1, 4, 6) through both entries, node.mjs
// (node:zlib) and browser.mjs (brotli-dec-wasm); v4 transforms and colours, and the 3.x rules kept.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { readPln as readNode, nodeBrotli } from '../src/node.mjs';
import { readPln as readBrowser, wasmBrotli } from '../src/browser.mjs';
import { readPln as readBare } from '../src/index.mjs';
import { conformanceJson } from '../src/report.mjs';
import { Cursor } from '../src/varint.mjs';
import { VALID, golden, manifest, suiteFile, caseJson, varint, f32, f64, u32, assemble4 as assemble, outcome, expectBoth } from './files.mjs';

/** @typedef {{type: string, payload: Uint8Array}} Chunk */

/** @param {Uint8Array} bytes @returns {Chunk[]} */
function chunksOf(bytes) {
  const out = [];
  for (let pos = 8; pos < bytes.length;) {
    const length = new DataView(bytes.buffer, bytes.byteOffset).getUint32(pos + 4, true);
    out.push({ type: String.fromCharCode(...bytes.subarray(pos, pos + 4)), payload: bytes.slice(pos + 8, pos + 8 + length) });
    pos += 12 + length;
  }
  return out;
}

/** §8, version 4: the shortest code of each of the 12 entries, then their values. @param {number[]} m 16 entries */
function codedTransform(m) {
  let codes = 0;
  /** @type {number[]} */
  const values = [];
  for (let i = 0; i < 12; i++) {
    const v = m[i];
    const code = Object.is(v, 0) ? 0 : v === 1 ? 1 : Object.is(Math.fround(v), v) ? 2 : 3;
    codes |= code << (2 * i);
    if (code === 2) values.push(...f32(v));
    if (code === 3) values.push(...f64(v));
  }
  return [codes & 0xff, (codes >>> 8) & 0xff, codes >>> 16, ...values];
}

/** An OBJT payload of version 3 or 4. @param {{index: number, parent?: number | null, name?: string, transform?: number[] | null, rest?: number[]}} o */
function objt({ index, parent = null, name = '', transform = null, rest = [] }) {
  const n = [...new TextEncoder().encode(name)];
  return Uint8Array.from([...varint(index), ...varint(parent === null ? 0 : parent + 1), transform ? 1 : 0, ...varint(n.length), ...n,
    ...(transform ?? []), ...rest]);
}

/**
 * The PLNS or GRUP head of a version 3 payload up to its method, the method, its raw size and the
 * stored bytes.
 * @param {Chunk} chunk
 */
function splitCompressed(chunk) {
  const c = new Cursor(chunk.payload);
  if (chunk.type === 'PLNS') { c.varint(); c.varint(); } else { c.varint(); c.varint(); c.u8(); }
  const head = chunk.payload.slice(0, c.pos);
  const method = c.u8();
  const rawSize = c.varint();
  const stored = chunk.payload.subarray(c.pos);
  const raw = method === 1 ? new Uint8Array(zlib.inflateSync(stored)) : stored;
  return { head, method, rawSize, raw };
}

/** @param {Uint8Array} head @param {number} method @param {number} rawSize @param {ArrayLike<number>} stored */
const compressed = (head, method, rawSize, stored) => Uint8Array.from([...head, method, ...varint(rawSize), ...Array.from(stored)]);

/** @param {Uint8Array} raw */
const brotli = (raw) => new Uint8Array(zlib.brotliCompressSync(raw));

/**
 * A 3.x file (major 3) rewritten as 4.0 with the same content: version 4.0, every PLNS and GRUP
 * payload Brotli (method 2), transforms coded entry by entry, a cOLR of one colour where all its
 * colours are one, no iNDX (offsets move) and an empty PEND.
 * @param {Uint8Array} bytes
 */
function upgrade(bytes) {
  /** @type {Chunk[]} */
  const out = [];
  for (const ch of chunksOf(bytes)) {
    const p = ch.payload;
    if (ch.type === 'PHDR') out.push({ type: 'PHDR', payload: Uint8Array.from([4, 0, ...p.subarray(2)]) });
    else if (ch.type === 'OBJT') {
      const c = new Cursor(p);
      const index = c.varint();
      const parent = c.varint();
      const flags = c.u8();
      const name = c.take(c.varint());
      let transform = null;
      if (flags & 1) {
        const m = [];
        for (let i = 0; i < 16; i++) m.push(c.f64());
        transform = codedTransform(m);
      }
      out.push({ type: 'OBJT', payload: Uint8Array.from([...varint(index), ...varint(parent), flags, ...varint(name.length), ...name, ...(transform ?? []), ...p.subarray(c.pos)]) });
    } else if (ch.type === 'PLNS' || ch.type === 'GRUP') {
      const { head, rawSize, raw } = splitCompressed(ch);
      out.push({ type: ch.type, payload: compressed(head, 2, rawSize, brotli(raw)) });
    } else if (ch.type === 'cOLR') {
      const rgba = p.subarray(8);
      let one = rgba.length >= 4;
      for (let i = 4; i < rgba.length; i++) if (rgba[i] !== rgba[i % 4]) one = false;
      out.push({ type: 'cOLR', payload: one ? p.slice(0, 12) : p });
    } else if (ch.type === 'iNDX') continue;
    else if (ch.type === 'PEND') out.push({ type: 'PEND', payload: new Uint8Array(0) });
    else out.push(ch);
  }
  return assemble(out);
}

const readers = /** @type {const} */ ([['node', readNode], ['browser', readBrowser]]);

const v3files = fs.readdirSync(VALID).filter((f) => f.endsWith('.pln')).sort().filter((f) => {
  const v = chunksOf(golden(f))[0].payload;
  return v[0] === 3 && v[1] <= 4;
});

test('3.x golden files to rewrite', () => assert.ok(v3files.length >= 15, `${v3files.length}`));

for (const name of v3files) {
  test(`${name} as 4.0 (Brotli, coded transforms, one colour) reads as the original`, () => {
    const bytes = golden(name);
    const v4 = upgrade(bytes);
    const want = conformanceJson(readNode(bytes));
    want.header.version = [4, 0];
    for (const [entry, read] of readers) {
      const file = read(v4);
      assert.deepEqual(conformanceJson(file), want, `${entry} entry`);
      assert.ok(file.container.groups.every((/** @type {any} */ g) => g.refs.length > 0));
    }
  });
}

/** cube_v3.pln: one object, one convex group (kind 0), as 4.0; the group's references. */
const CUBE = golden('cube_v3.pln');
/** Its chunks, as 3.0, without the iNDX (so that chunks may change size) and with an empty PEND. */
const cube3 = chunksOf(CUBE).filter((c) => c.type !== 'iNDX').map((c) => (c.type === 'PEND' ? { type: 'PEND', payload: new Uint8Array(0) } : c));
const cube4 = chunksOf(upgrade(CUBE));
const cubeRefs = readNode(CUBE).container.groups[0].refs.length;

/**
 * cube4 (or `chunks`) with chunk `type` replaced, or, with `after`, a chunk of type `after` added
 * after it.
 * @param {string} type @param {Uint8Array} payload
 * @param {{after?: string, chunks?: Chunk[]}} [options]
 */
function cubeWith(type, payload, { after = '', chunks = cube4 } = {}) {
  const out = [];
  for (const ch of chunks) {
    if (ch.type === type && after) out.push(ch, { type: after, payload });
    else out.push(ch.type === type ? { type, payload } : ch);
  }
  return assemble(out);
}

/** cube4 with its GRUP's method, raw size or stored bytes changed. */
function cubeGroup({ method = 2, delta = 0, stored = /** @type {((s: Uint8Array, raw: Uint8Array) => ArrayLike<number>) | null} */ (null) } = {}) {
  const g = /** @type {Chunk} */ (chunksOf(CUBE).find((c) => c.type === 'GRUP'));
  const { head, rawSize, raw } = splitCompressed(g);
  const s = brotli(raw);
  return cubeWith('GRUP', compressed(head, method, rawSize + delta, stored ? stored(s, raw) : s));
}

test('Brotli payloads: a valid stream reads through both entries', () => {
  expectBoth(cubeGroup(), 'ok');
  expectBoth(cubeGroup({ stored: (s) => s }), 'ok');
});

test('Brotli, §6 step 6: a truncated stream is SIZE_MISMATCH, an invalid one BAD_COMPRESSION', () => {
  for (let cut = 1; cut <= 3; cut++) expectBoth(cubeGroup({ stored: (s) => s.subarray(0, s.length - cut) }), 'SIZE_MISMATCH');
  expectBoth(cubeGroup({ stored: (s) => s.subarray(0, 1) }), 'SIZE_MISMATCH');
  // an empty stored part: raw size over 1100 × 0 is the ratio limit first
  expectBoth(cubeGroup({ stored: () => [] }), 'LIMIT_EXCEEDED');
  // a stream whose first bytes are invalid (reserved padding bits set: ERROR_FORMAT_PADDING_2)
  expectBoth(cubeGroup({ stored: (s) => [0xff, 0xff, 0xff, 0xff, ...s.subarray(4)] }), 'BAD_COMPRESSION');
  // every single-byte change of the stream is read, or refused as one of §6's two codes
  const g = /** @type {Chunk} */ (chunksOf(CUBE).find((c) => c.type === 'GRUP'));
  const n = brotli(splitCompressed(g).raw).length;
  for (let at = 0; at < n; at++) {
    const bytes = cubeGroup({ stored: (s) => { const t = s.slice(); t[at] ^= 0x5a; return t; } });
    const a = outcome(bytes, readNode);
    assert.ok(['ok', 'BAD_COMPRESSION', 'SIZE_MISMATCH', 'BAD_PAYLOAD', 'BAD_GROUP_STRUCTURE', 'BAD_PLANE_REFERENCE', 'EMPTY_POLYTOPE', 'UNBOUNDED_POLYTOPE'].includes(a), `byte ${at}: ${a}`);
    if (a === 'BAD_COMPRESSION' || a === 'SIZE_MISMATCH') assert.equal(outcome(bytes, readBrowser), a, `byte ${at}: the browser entry`);
  }
});

test('Brotli, §6 step 6: bytes after the stream are BAD_COMPRESSION; an output of another size SIZE_MISMATCH', () => {
  expectBoth(cubeGroup({ stored: (s) => [...s, 0] }), 'BAD_COMPRESSION');
  expectBoth(cubeGroup({ stored: (s) => [...s, ...s] }), 'BAD_COMPRESSION');
  expectBoth(cubeGroup({ delta: 1 }), 'SIZE_MISMATCH');
  expectBoth(cubeGroup({ delta: -1 }), 'SIZE_MISMATCH');
  expectBoth(cubeGroup({ delta: -2 }), 'SIZE_MISMATCH');
  // bytes after the stream come first, whatever the output's size
  expectBoth(cubeGroup({ delta: 1, stored: (s) => [...s, 0] }), 'BAD_COMPRESSION');
  // a stream the stored bytes end inside is SIZE_MISMATCH even where its output fell short
  expectBoth(cubeGroup({ delta: 5, stored: (s) => s.subarray(0, s.length - 1) }), 'SIZE_MISMATCH');
});

test('§6 steps 1 and 4: method 2 only from version 4, other methods refused, the ratio limit on Brotli', () => {
  expectBoth(cubeGroup({ method: 3 }), 'BAD_COMPRESSION');
  // a 3.0 file with a Brotli payload (Appendix A: method 2 does not exist there)
  const chunks = cube3;
  const g = /** @type {Chunk} */ (chunks.find((c) => c.type === 'GRUP'));
  const { head, rawSize, raw } = splitCompressed(g);
  const v3 = assemble(chunks.map((c) => (c === g ? { type: 'GRUP', payload: compressed(head, 2, rawSize, brotli(raw)) } : c)));
  expectBoth(v3, 'BAD_COMPRESSION');
  // raw size above ratio × stored size, before anything is decompressed
  const s = brotli(raw).length;
  expectBoth(cubeGroup({ delta: 1100 * s - rawSize + 1 }), 'LIMIT_EXCEEDED');
  expectBoth(cubeGroup({ delta: 1100 * s - rawSize }), 'SIZE_MISMATCH');
  // a stream of 10 MB in a few bytes, where raw size is 8: stopped at 9 bytes of output
  const bomb = brotli(new Uint8Array(10_000_000));
  expectBoth(cubeGroup({ stored: () => bomb }), 'SIZE_MISMATCH');
  // index.mjs alone has no Brotli decoder: such payloads cannot be read
  assert.equal(outcome(cubeGroup(), readBare), 'BAD_COMPRESSION');
  assert.equal(outcome(cubeGroup(), readBare, { brotli: nodeBrotli }), 'ok');
});

test('the Brotli decompressors stop at maxOutputLength (raw size + 1)', () => {
  const big = new Uint8Array(20_000_000);
  big.fill(7);
  const bomb = brotli(big);
  for (const fn of [nodeBrotli, wasmBrotli]) {
    for (const max of [1, 64, 100, 65_537]) {
      assert.throws(() => fn(bomb, max), (/** @type {any} */ e) => e.tooLong === true, `${fn.name} ${max}`);
    }
    const exact = /** @type {{output: Uint8Array, consumed: number}} */ (fn(brotli(big.subarray(0, 1000)), 1001));
    assert.equal(exact.output.length, 1000);
    assert.equal(exact.consumed, brotli(big.subarray(0, 1000)).length);
    // an output of exactly maxOutputLength: returned (the caller sees it pass raw size) or refused
    try {
      assert.equal(/** @type {{output: Uint8Array}} */ (fn(brotli(big.subarray(0, 1001)), 1001)).output.length, 1001, fn.name);
    } catch (e) {
      assert.equal(/** @type {any} */ (e).tooLong, true, fn.name);
    }
    assert.throws(() => fn(bomb.subarray(0, bomb.length - 1), 100), (/** @type {any} */ e) => e.truncated === true || e.tooLong === true, fn.name);
    assert.throws(() => fn(Uint8Array.of(0xff, 0xff, 0xff, 0xff), 100), (/** @type {any} */ e) => !e.truncated && !e.tooLong, fn.name);
    const empty = /** @type {{output: Uint8Array, consumed: number}} */ (fn(brotli(new Uint8Array(0)), 1));
    assert.deepEqual([empty.output.length, empty.consumed], [0, brotli(new Uint8Array(0)).length]);
  }
});

test('version 4 files of zlib payloads read too; version 4.0 kinds 0-8, 4.1 kinds 0-9, 4.2 kinds 0-10, 4.3 skips kind 12, major 7 refused', () => {
  const zlibbed = assemble(chunksOf(upgrade(CUBE)).map((c) => {
    if (c.type !== 'GRUP') return c;
    const g = /** @type {Chunk} */ (chunksOf(CUBE).find((k) => k.type === 'GRUP'));
    const { head, rawSize, raw } = splitCompressed(g);
    return { type: 'GRUP', payload: compressed(head, 1, rawSize, zlib.deflateSync(raw)) };
  }));
  expectBoth(zlibbed, 'ok');
  const kind = (/** @type {number} */ k, /** @type {number} */ minor) => assemble(cube4.map((c) => {
    if (c.type === 'PHDR') return { type: 'PHDR', payload: Uint8Array.from([4, minor, ...c.payload.subarray(2)]) };
    if (c.type !== 'GRUP') return c;
    const p = c.payload.slice();
    const at = new Cursor(p);
    at.varint(); at.varint();
    p[at.pos] = k;
    return { type: 'GRUP', payload: p };
  }));
  expectBoth(kind(9, 0), 'UNKNOWN_GROUP_KIND');
  // 4.1 knows kind 9 (§9.13): the cube's body, no kind data after the roles, is read as a shell
  // walk and ends inside its counts
  expectBoth(kind(9, 1), 'BAD_PAYLOAD');
  expectBoth(kind(10, 1), 'UNKNOWN_GROUP_KIND');
  expectBoth(kind(10, 0), 'UNKNOWN_GROUP_KIND');
  assert.deepEqual(readNode(kind(0, 1)).findings, new Set());
  assert.deepEqual(readNode(kind(0, 2)).findings, new Set());
  // 4.2 knows kind 10 (§9.14): read as a shell walk, ending inside its counts; kind 12 unknown
  expectBoth(kind(10, 2), 'BAD_PAYLOAD');
  expectBoth(kind(9, 2), 'BAD_PAYLOAD');
  expectBoth(kind(12, 2), 'UNKNOWN_GROUP_KIND');
  const skipped = readNode(kind(12, 3));
  assert.deepEqual([...skipped.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  assert.deepEqual(readNode(cubeGroup()).findings, new Set());
  assert.deepEqual(readNode(cubeGroup()).version, [4, 0]);
  // majors 5 and 6 are read since versions 5.0 and 6.0 (§5), each its own layout; 0 and 7 on are refused
  for (const major of [0, 7, 255]) expectBoth(cubeWith('PHDR', Uint8Array.from([major, 0, ...cube4[0].payload.subarray(2)])), 'UNSUPPORTED_VERSION');
});

/** @param {number[]} transform the OBJT transform field @param {number[]} [rest] */
const cubeObject = (transform, rest = []) => cubeWith('OBJT', objt({ index: 0, name: 'o', transform, rest }));

/** The transform read from cube4 with this transform field. @param {number[]} field */
const transformOf = (field) => readNode(cubeObject(field)).objects[0].transform;

test('§8 version 4: codes LSB first, entry by entry, values in entry order, last row 0 0 0 1', () => {
  // identity: codes 1 at entries 0, 5, 10 (bits 0, 10, 20)
  assert.deepEqual(transformOf([0x01, 0x04, 0x10]), [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]);
  // all zero (no check of invertibility)
  assert.deepEqual(transformOf([0, 0, 0]), [0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1]);
  // a translation in f32: code 2 at entries 3, 7, 11 (bits 7, 15, 23 set): 15 bytes
  const t32 = [0x81, 0x84, 0x90, ...f32(0.1), ...f32(-2.5), ...f32(1e30)];
  assert.equal(t32.length, 15);
  assert.deepEqual(transformOf(t32), [1, 0, 0, Math.fround(0.1), 0, 1, 0, -2.5, 0, 0, 1, Math.fround(1e30), 0, 0, 0, 1]);
  // in f64 (code 3): 27 bytes
  const t64 = [0xc1, 0xc4, 0xd0, ...f64(0.1), ...f64(-2.5), ...f64(1e300)];
  assert.equal(t64.length, 27);
  assert.deepEqual(transformOf(t64), [1, 0, 0, 0.1, 0, 1, 0, -2.5, 0, 0, 1, 1e300, 0, 0, 0, 1]);
  // every entry, codes 3 2 1 0 3 2 1 0 ...: values f64, f32, -, -, f64, f32 ... in entry order
  const mixed = [0b00011011, 0b00011011, 0b00011011];
  const vals = [1.5, 2.25, 7.1, -0.5, 1e-300, Math.fround(3.3)];
  mixed.push(...f64(vals[0]), ...f32(vals[1]), ...f64(vals[2]), ...f32(vals[3]), ...f64(vals[4]), ...f32(vals[5]));
  assert.deepEqual(transformOf(mixed), [1.5, 2.25, 1, 0, 7.1, -0.5, 1, 0, 1e-300, vals[5], 1, 0, 0, 0, 0, 1]);
  // −0.0 as an f32 stays −0.0; code 0 is +0.0
  const neg = transformOf([0x02, 0, 0, ...f32(-0)]);
  assert.ok(Object.is(/** @type {number[]} */ (neg)[0], -0) && Object.is(/** @type {number[]} */ (neg)[1], 0));
  // fields a newer minor version appends after the transform are ignored
  assert.deepEqual(readNode(cubeObject([0x01, 0x04, 0x10], [9, 9, 9])).objects[0].transform, transformOf([0x01, 0x04, 0x10]));
  // and the world: the cube translated
  const world = readNode(cubeObject(t64)).mesh();
  const plain = readNode(cubeObject([0x01, 0x04, 0x10])).mesh();
  assert.ok(Math.abs(world.positions64[1] - plain.positions64[1] + 2.5) < 1e-12);
});

test('§8 version 4: a payload ending inside the codes or values BAD_PAYLOAD, a non-finite entry BAD_OBJECT', () => {
  expectBoth(cubeObject([]), 'BAD_PAYLOAD');
  expectBoth(cubeObject([0x01, 0x04]), 'BAD_PAYLOAD');
  expectBoth(cubeObject([0x81, 0x84, 0x90, ...f32(1), ...f32(2)]), 'BAD_PAYLOAD');
  expectBoth(cubeObject([0xc1, 0xc4, 0xd0, ...f64(1), ...f64(2), 0, 0, 0, 0, 0, 0, 0]), 'BAD_PAYLOAD');
  expectBoth(cubeObject([0x02, 0, 0, ...f32(NaN)]), 'BAD_OBJECT');
  expectBoth(cubeObject([0x03, 0, 0, ...f64(Infinity)]), 'BAD_OBJECT');
  expectBoth(cubeObject([0x80, 0x80, 0x80, ...f32(1), ...f32(-Infinity), ...f32(1)]), 'BAD_OBJECT');
  // ending inside the values comes before a wrong index (§8 step 4 before 5)
  expectBoth(cubeWith('OBJT', objt({ index: 7, transform: [0x03, 0, 0, 1, 2] })), 'BAD_PAYLOAD');
  expectBoth(cubeWith('OBJT', objt({ index: 7, transform: [0x01, 0x04, 0x10] })), 'BAD_OBJECT');
});

test('Appendix A: a version 3 transform is still 16 × f64 with its last row checked', () => {
  const chunks = cube3;
  const v3object = (/** @type {number[]} */ m) => assemble(chunks.map((c) => (c.type === 'OBJT' ? { type: 'OBJT', payload: objt({ index: 0, transform: m.flatMap(f64) }) } : c)));
  const id = [1, 0, 0, 5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];
  assert.deepEqual(readNode(v3object(id)).objects[0].transform, id);
  expectBoth(v3object([...id.slice(0, 15), 2]), 'BAD_OBJECT');
  expectBoth(v3object([...id.slice(0, 12), 0, 1, 0, 1]), 'BAD_OBJECT');
  // a v4 coded transform in a v3 file ends inside its 128 bytes
  expectBoth(assemble(chunks.map((c) => (c.type === 'OBJT' ? { type: 'OBJT', payload: objt({ index: 0, transform: [0x01, 0x04, 0x10] }) } : c))), 'BAD_PAYLOAD');
});

/** A cOLR payload. @param {number} group @param {number} count @param {number[]} rgba */
const colr = (group, count, rgba) => Uint8Array.from([...u32(group), ...u32(count), ...rgba]);

test('§10.1 version 4: a 12-byte cOLR is one colour for every reference, reported expanded', () => {
  const one = readNode(cubeWith('GRUP', colr(0, cubeRefs, [10, 20, 30, 255]), { after: 'cOLR' }));
  const each = readNode(cubeWith('GRUP', colr(0, cubeRefs, Array(cubeRefs).fill([10, 20, 30, 255]).flat()), { after: 'cOLR' }));
  assert.deepEqual(one.container.colours, each.container.colours);
  assert.equal(one.container.colours[0].rgba.length, 4 * cubeRefs);
  assert.deepEqual(conformanceJson(one).colours, conformanceJson(each).colours);
  const fc = /** @type {Uint8Array} */ (/** @type {any} */ (one.meshes[0]).faceColors);
  assert.ok(fc.length > 0 && fc.every((v, i) => v === [10, 20, 30, 255][i % 4]));
  assert.deepEqual(fc, /** @type {any} */ (each.meshes[0]).faceColors);
  for (const [, read] of readers) assert.deepEqual(conformanceJson(read(cubeWith('GRUP', colr(0, cubeRefs, [1, 2, 3, 4]), { after: 'cOLR' }))).colours, [{ group: 0, rgba: Array(cubeRefs).fill([1, 2, 3, 4]) }]);
});

test('§10.1 version 4: the checks of a cOLR, one colour or one per reference', () => {
  const withColours = (/** @type {Uint8Array} */ p) => cubeWith('GRUP', p, { after: 'cOLR' });
  expectBoth(withColours(colr(0, cubeRefs + 1, [1, 2, 3, 4])), 'BAD_COLOURS'); // count other than ref_count
  expectBoth(withColours(colr(1, cubeRefs, [1, 2, 3, 4])), 'BAD_COLOURS'); // group not read yet
  expectBoth(withColours(colr(0, 0xffffffff, [1, 2, 3, 4])), 'BAD_COLOURS');
  expectBoth(withColours(colr(0, cubeRefs, [1, 2, 3, 4, 5])), 'BAD_PAYLOAD'); // 13 bytes: ends inside count colours
  expectBoth(withColours(colr(0, cubeRefs, [1, 2, 3])), 'BAD_PAYLOAD');
  expectBoth(withColours(colr(0, 1, [1, 2, 3, 4, 5, 6])), 'BAD_COLOURS'); // count 1: bytes after its colour
  expectBoth(withColours(colr(0, cubeRefs, Array(4 * cubeRefs + 1).fill(9))), 'BAD_COLOURS');
  expectBoth(withColours(colr(0, cubeRefs, [])), 'BAD_PAYLOAD');
  expectBoth(withColours(Uint8Array.from(u32(0))), 'BAD_PAYLOAD');
});

test('Appendix A: a version 3 cOLR of 12 bytes and count above 1 ends inside its colours', () => {
  const chunks = cube3;
  const v3 = (/** @type {Uint8Array} */ p) => cubeWith('GRUP', p, { after: 'cOLR', chunks });
  expectBoth(v3(colr(0, cubeRefs, [1, 2, 3, 4])), 'BAD_PAYLOAD');
  expectBoth(v3(colr(0, cubeRefs, Array(4 * cubeRefs).fill(1))), 'ok');
});

test('the 4.0 conformance cases through both entries (the browser entry included for invalid files)', () => {
  const cases = manifest().filter(([file]) => /_v4_0\.pln$|\/xv4_/.test(file));
  assert.ok(cases.length >= 12, `${cases.length} cases`);
  for (const [file, expected] of cases) expectBoth(suiteFile(file), expected === 'ok' ? 'ok' : caseJson(file).error);
  // scene_transforms_v4_0: −0.0 entries coded as f32 stay −0.0; the first cube's one colour expanded
  const scene = readBrowser(fs.readFileSync(path.join(VALID, 'scene_transforms_v4_0.pln')));
  const c = /** @type {number[]} */ (scene.objects[3].transform);
  assert.ok(Object.is(c[1], -0) && Object.is(c[11], -0) && c[0] === -1);
  assert.equal(scene.container.colours[0].rgba.length, 4 * scene.container.groups[0].refs.length);
});
