// Files and fields built the way the spec lays them out, shared by the tests that make their own
// .pln files: the fields (§2: varints, zigzag, little-endian floats and u32s, plane triplets), the
// chunk framing with its CRC (§4.1: u32 lengths before version 5; from version 5 on, varint lengths
// after PHDR), a file of version 3 or 4 and one of version 5 (§5, §7, §8, §9.1, §9.2, §10.1), a
// group's raw body (§6); the conformance suite's golden files, manifest and expected reports; the
// try-read helpers (an error code or 'ok', through one entry or both; a shell's report) and
// planefmt's decoding of a file. No kind's encoder, prediction or reference decoder is here: each
// test writes those for its own kind from its own section of the spec.
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { readPln as readNode, PlnError } from '../src/node.mjs';
import { readPln as readBrowser } from '../src/browser.mjs';
import { conformanceJson } from '../src/report.mjs';
import { crc32 } from '../src/crc32.mjs';
import { Cursor } from '../src/varint.mjs';
import { PYTHON } from '../bench/corpus.mjs';

const HERE = path.dirname(fileURLToPath(import.meta.url));

// ---------------------------------------------------------------------------------------------
// The conformance suite

/** The conformance suite (conformance/ of the repository, or PLN_CONFORMANCE: another worktree's). */
export const SUITE = process.env.PLN_CONFORMANCE ?? path.resolve(HERE, '../../conformance');
/** The linear-time tests' limit in ms: a hang guard far above normal, not a verdict on speed. Their
 *  reads of 12,000 to 200,000 triangles took 0.4 to 2.4 s on a loaded 2-core machine; quadratic work
 *  on 200,000 corners is some 10^10 steps. */
export const HANG_MS = 60000;
/** Its valid (golden) files. */
export const VALID = path.join(SUITE, 'valid');

/** A file of the suite, its bytes. @param {string} name a path under conformance/, as the manifest gives it */
export const suiteFile = (name) => new Uint8Array(fs.readFileSync(path.join(SUITE, name)));
/** What the suite says of a case: the .json beside its .pln. @param {string} name the .pln's path under conformance/ */
export const caseJson = (name) => JSON.parse(fs.readFileSync(path.join(SUITE, name.replace(/\.pln$/, '.json')), 'utf8'));
/** A golden file's bytes. @param {string} name a file of conformance/valid */
export const golden = (name) => new Uint8Array(fs.readFileSync(path.join(VALID, name)));

/** The rows of conformance/manifest.tsv after its head, each split at its tabs (file, expected, …). */
export const manifest = () => fs.readFileSync(path.join(SUITE, 'manifest.tsv'), 'utf8').split('\n').slice(1).filter(Boolean)
  .map((line) => line.split('\t'));

// ---------------------------------------------------------------------------------------------
// Fields (§2)

/** The file signature (§3). */
export const SIGNATURE = [0x89, 0x50, 0x4c, 0x4e, 0x0d, 0x0a, 0x1a, 0x0a];

/** @param {number | bigint} v @returns {number[]} minimal LEB128 (a number exact up to 2^53; a bigint beyond) */
export function varint(v) {
  let b = BigInt(v);
  const out = [];
  while (b >= 0x80n) { out.push(Number(b % 128n) | 0x80); b /= 128n; }
  out.push(Number(b));
  return out;
}
/** Each value's varint, one after another. @param {(number | bigint)[]} values */
export const varints = (values) => values.flatMap(varint);
/** Zigzag (§2.2) of a signed bigint. @param {bigint} d */
export const zigzag = (d) => (d >= 0n ? 2n * d : -2n * d - 1n);
/** The signed bigint of a zigzag. @param {bigint} z */
export const unzigzag = (z) => (z % 2n === 0n ? z / 2n : -(z + 1n) / 2n);
export const f32 = (/** @type {number} */ v) => [...new Uint8Array(Float32Array.of(v).buffer)];
export const f64 = (/** @type {number} */ v) => [...new Uint8Array(Float64Array.of(v).buffer)];
export const u32 = (/** @type {number} */ v) => [...new Uint8Array(Uint32Array.of(v).buffer)];

/** A varint read as a bigint, any length (not checked for minimality). @param {Cursor} c */
export function bigVarint(c) {
  let v = 0n;
  for (let shift = 0n; ; shift += 7n) {
    const byte = c.u8();
    v += BigInt(byte & 0x7f) << shift;
    if (byte < 0x80) return v;
  }
}

/** The triplet (ν, φ, h) of the plane with normal n through point p (§2.3). @param {number[]} n @param {number[]} p */
export function triplet(n, p) {
  const l = Math.hypot(...n);
  const w = n.map((c) => c / l);
  const nu = Math.acos(Math.max(-1, Math.min(1, w[2])));
  let phi = Math.atan2(w[1], w[0]);
  if (phi < 0) phi += 2 * Math.PI;
  if (phi >= 2 * Math.PI || nu === 0 || nu === Math.PI) phi = 0;
  return [nu, phi, w[0] * p[0] + w[1] * p[1] + w[2] * p[2]];
}

/** §8, version 4: a transform's twelve entries, each as an f64 (code 3). @param {number[]} m 12 or 16 entries, row by row */
export function transformBytes(m) {
  return [0xff, 0xff, 0xff, ...m.slice(0, 12).flatMap(f64)];
}

/** §9.2's common body: ref_count, the references as differences, the role bits. @param {number[]} refs @param {number[]} [bounding] */
export function common(refs, bounding = []) {
  const roles = new Array(Math.ceil(refs.length / 8)).fill(0);
  for (const i of bounding) roles[i >> 3] |= 1 << (i & 7);
  return [...varint(refs.length), ...refs.flatMap((r, i) => varint(i === 0 ? r : r - refs[i - 1])), ...roles];
}

// ---------------------------------------------------------------------------------------------
// Chunks (§4) and files

/** @param {Uint8Array[]} parts @returns {Uint8Array} */
function concat(parts) {
  const out = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
  let at = 0;
  for (const p of parts) { out.set(p, at); at += p.length; }
  return out;
}

/**
 * A file of version 3 or 4: the signature, then each chunk as type, u32 length, payload and the
 * CRC of type and payload.
 * @param {{type: string, payload: ArrayLike<number>}[]} chunks @returns {Uint8Array}
 */
export function assemble4(chunks) {
  const parts = [Uint8Array.from(SIGNATURE)];
  for (const { type, payload } of chunks) {
    const c = new Uint8Array(12 + payload.length);
    const v = new DataView(c.buffer);
    for (let i = 0; i < 4; i++) c[i] = type.charCodeAt(i);
    v.setUint32(4, payload.length, true);
    c.set(payload, 8);
    v.setUint32(8 + payload.length, crc32(c, 8, 8 + payload.length, crc32(c, 0, 4)), true);
    parts.push(c);
  }
  return concat(parts);
}

/**
 * A file of version 5 (§4.1): PHDR's length a u32, every later one a varint (or, where a chunk
 * gives `length`, those bytes as stored).
 * @param {{type: string, payload: ArrayLike<number>, length?: number[]}[]} chunks @returns {Uint8Array}
 */
export function assemble5(chunks) {
  const parts = [Uint8Array.from(SIGNATURE)];
  chunks.forEach(({ type, payload, length }, i) => {
    const tag = [...type].map((ch) => ch.charCodeAt(0));
    const tagged = new Uint8Array(tag.length + payload.length);
    tagged.set(tag);
    tagged.set(payload, tag.length);
    const crc = crc32(tagged, 0, tagged.length);
    const len = length ?? (i === 0 ? u32(payload.length) : varint(payload.length));
    parts.push(tagged.subarray(0, tag.length), Uint8Array.from(len), tagged.subarray(tag.length), Uint8Array.from(u32(crc)));
  });
  return concat(parts);
}

/**
 * @typedef {object} File4 a file of version 3 or 4
 * @property {ArrayLike<number>} planes (ν, φ, h) of each plane, one after another
 * @property {(number[] | null)[]} [objects] each a root, with a transform (coded the version 4
 *   way, every entry an f64) or none; one object without a transform by default
 * @property {{object?: number, kind: number, body: number[], method?: number}[]} groups each its
 *   object, kind and raw body (the common body included), stored with method 0, 1 or 2
 * @property {{group: number, rgba: number[]}[]} [colours] cOLR chunks
 * @property {[number, number]} version
 * @property {0 | 1} [coding] float32 (0) or float64 (1, the default) planes
 */

/** A file of version 3 or 4 (§5, §7, §8, §9.2, §10.1). @param {File4} f */
export function file4({ planes, objects = [null], groups, colours = [], version, coding = 1 }) {
  const header = [version[0], version[1], 0, 0, coding, 0, 0, 0, 1, ...f32(NaN), ...f32(NaN)];
  const plns = Array.from(planes).flatMap(coding === 0 ? f32 : f64);
  const chunks = [
    { type: 'PHDR', payload: header },
    { type: 'PLNS', payload: [...varint(0), ...varint(planes.length / 3), 0, ...varint(plns.length), ...plns] },
  ];
  objects.forEach((m, k) => {
    chunks.push({ type: 'OBJT', payload: [...varint(k), 0, m ? 1 : 0, 0, ...(m ? transformBytes(m) : [])] });
  });
  groups.forEach(({ object = 0, kind, body, method = 0 }, index) => {
    const raw = Uint8Array.from(body);
    const stored = method === 1 ? zlib.deflateSync(raw) : method === 2 ? zlib.brotliCompressSync(raw) : raw;
    chunks.push({ type: 'GRUP', payload: [...varint(index), ...varint(object), kind, method, ...varint(raw.length), ...stored] });
  });
  for (const { group, rgba } of colours) chunks.push({ type: 'cOLR', payload: [...u32(group), ...u32(rgba.length / 4), ...rgba] });
  chunks.push({ type: 'PEND', payload: [] });
  return assemble4(chunks);
}

/**
 * A file of version 5 (§4.1, §5): coding 1 (f64 triplets), the given planes in one PLNS (none
 * without planes), one object, groups with the kind, kind data and m references (the planes
 * 0 … m − 1, all face planes; m = 0 by default, §9.2), stored with method 0.
 * @param {{kind: number, data: number[], m?: number}[]} groups @param {number} minor
 * @param {number[][]} [planes]
 */
export function file5(groups, minor, planes = []) {
  const nan = f32(NaN);
  const plns = planes.flatMap(([nu, phi, h]) => [...f64(nu), ...f64(phi), ...f64(h)]);
  return assemble5([
    { type: 'PHDR', payload: [5, minor, 0, 1, 0, 0, 0, 1, ...nan, ...nan] },
    ...(planes.length ? [{ type: 'PLNS', payload: [0, ...varint(planes.length), 0, ...varint(plns.length), ...plns] }] : []),
    { type: 'OBJT', payload: [0, 0, 0, 0] },
    ...groups.map(({ kind, data, m = 0 }, i) => {
      const head = common(Array.from({ length: m }, (_, r) => r));
      return { type: 'GRUP', payload: [...varint(i), 0, kind, 0, ...varint(head.length + data.length), ...head, ...data] };
    }),
    { type: 'PEND', payload: [] },
  ]);
}

/**
 * Group `index`'s kind, method and raw body (its stored bytes decompressed, §6), found through the
 * chunk list readPln gives.
 * @param {Uint8Array} bytes @param {number} index @param {ReturnType<typeof readNode>} [f] the file, read already
 */
export function groupBody(bytes, index, f = readNode(bytes)) {
  const chunk = f.chunks.filter((c) => c.type === 'GRUP')[index];
  const payload = bytes.subarray(chunk.offset + chunk.size - 4 - chunk.length, chunk.offset + chunk.size - 4);
  const c = new Cursor(payload);
  c.varint(); c.varint();
  const kind = c.u8();
  const method = c.u8();
  c.varint();
  const stored = payload.subarray(c.pos);
  const raw = method === 0 ? stored : method === 1 ? zlib.inflateSync(stored) : zlib.brotliDecompressSync(stored);
  return { kind, method, body: new Uint8Array(raw) };
}

// ---------------------------------------------------------------------------------------------
// Reading

/**
 * The error code of reading `bytes`, or 'ok'.
 * @param {Uint8Array} bytes @param {typeof readNode} [read] @param {import('../src/index.mjs').ReadOptions} [options]
 */
export function outcome(bytes, read = readNode, options = {}) {
  try {
    read(bytes, options);
    return 'ok';
  } catch (err) {
    if (err instanceof PlnError) return err.code;
    throw err;
  }
}

/** Both entries (node.mjs and browser.mjs) give `code`. @param {Uint8Array} bytes @param {string} code @param {string} [what] */
export function expectBoth(bytes, code, what = '') {
  assert.equal(outcome(bytes, readNode), code, what ? `${what} (node.mjs)` : 'node.mjs');
  assert.equal(outcome(bytes, readBrowser), code, what ? `${what} (browser.mjs)` : 'browser.mjs');
}

/**
 * Both entries give an outcome the manifest allows: 'ok', or one of its codes (separated by |).
 * @param {Uint8Array} bytes @param {string} expected the manifest's column @param {string} name
 */
export function expectListed(bytes, expected, name) {
  const want = expected === 'ok' ? ['ok'] : expected.split('|');
  for (const read of [readNode, readBrowser]) assert.ok(want.includes(outcome(bytes, read)), `${name}: ${outcome(bytes, read)}, expected ${expected}`);
}

/**
 * The report of group `group`'s shell (both entries read it alike): its integer coordinates (or
 * table values) and triangles.
 * @param {Uint8Array} bytes
 */
export function shellOf(bytes, group = 0) {
  const json = conformanceJson(readNode(bytes));
  assert.deepEqual(conformanceJson(readBrowser(bytes)), json, 'browser.mjs reads it alike');
  const { grid, facets } = json.groups[group].shell;
  return { grid: /** @type {number[][]} */ (grid), tris: facets.map((/** @type {number[]} */ t) => t.slice(1)), json };
}

/** planefmt's decoding (planefmt_decode.py): world-frame vertices and triangles. @param {string} file */
export function planefmtDecoding(file) {
  const out = execFileSync(PYTHON, [path.join(HERE, 'planefmt_decode.py'), file], { maxBuffer: 1 << 30 });
  const nl = out.indexOf(10);
  const head = JSON.parse(out.subarray(0, nl).toString());
  const body = out.subarray(nl + 1);
  const buf = new ArrayBuffer(body.length);
  new Uint8Array(buf).set(body);
  return {
    positions: new Float64Array(buf, 0, 3 * head.vertices),
    indices: new Uint32Array(buf, 24 * head.vertices, 3 * head.triangles),
  };
}

// ---------------------------------------------------------------------------------------------
// Files that cost more than their size: the decode budget of §12.4

/**
 * §9.13 kind data of a walk of `t` ≥ 2 triangles fanned round corner 0: the root's child across its
 * edge 0, every other triangle's across its edge 1, each naming one new corner; every corner explicit
 * at 0, 0, 0 (V = t + 2), every triangle free. About five bytes a triangle, all alike.
 * @param {number} t @returns {Uint8Array}
 */
export function fanWalk(t) {
  const v = t + 2;
  const head = Uint8Array.from([...varint(v), ...varint(t), 3, 1]);
  const out = new Uint8Array(head.length + (t - 2) + 1 + 3 + t + Math.ceil(v / 8) + 1 + 16 + 3 * v);
  out.set(head);
  let at = head.length;
  out.fill(4, at, at + t - 2); // attached, a child across edge 1, a new corner
  at += t - 2 + 1 + 3 + t; // the last symbol 0, the root's three escapes 0, the faces 0 (free)
  out.fill(0xff, at, at + (v >> 3));
  if (v % 8) out[at + (v >> 3)] = (1 << (v % 8)) - 1;
  at += Math.ceil(v / 8) + 1; // the flags, the mode 0
  out.set([0, 0, 0, 1].flatMap(f32), at); // the grid: origin 0, 0, 0, step 1
  return out; // the residuals: 3V zeros
}

/** @param {Uint8Array} raw @param {number} method 0 stored, 1 zlib, 2 Brotli (§6) */
export const packed = (raw, method) => (method === 1 ? zlib.deflateSync(raw, { level: 9 }) : method === 2 ? zlib.brotliCompressSync(raw) : raw);

/**
 * A version 5.0 file: its header (coding, widths, h range for codings 2 and 3), the PLNS payloads
 * given, `objects` objects, then the groups, each its object, kind, raw body (the common body
 * included) and method.
 * @param {{groups: {object?: number, kind: number, body: Uint8Array, method?: number}[], blocks?: Uint8Array[],
 *   coding?: number, bits?: number[], hRange?: number[], objects?: number}} f
 */
export function budgetFile({ groups, blocks = [], coding = 0, bits = [0, 0, 0], hRange = [], objects = 1 }) {
  const head = [5, 0, 0, coding, ...bits, 1, ...hRange.flatMap(f64), ...f32(NaN), ...f32(NaN)];
  return assemble5([
    { type: 'PHDR', payload: head },
    ...blocks.map((payload) => ({ type: 'PLNS', payload })),
    ...Array.from({ length: objects }, (_, k) => ({ type: 'OBJT', payload: [...varint(k), 0, 0, 0] })),
    ...groups.map(({ object = 0, kind, body, method = 0 }, i) => {
      const stored = packed(body, method);
      const payload = new Uint8Array(stored.length + 16);
      const h = [...varint(i), ...varint(object), kind, method, ...varint(body.length)];
      payload.set(h);
      payload.set(stored, h.length);
      return { type: 'GRUP', payload: payload.subarray(0, h.length + stored.length) };
    }),
    { type: 'PEND', payload: [] },
  ]);
}

/** One fan walk of `t` triangles (group 0, no reference) and `copies` copies of it (§9.15). */
export function walkFile(/** @type {number} */ t, method = 1, copies = 0) {
  const walk = { kind: 9, body: Uint8Array.from([0, ...fanWalk(t)]), method };
  return budgetFile({ groups: [walk, ...Array.from({ length: copies }, () => ({ kind: 11, body: Uint8Array.of(0, 0) }))] });
}

/** §7.1: `count` float32 planes (0, 0, 0) from `first` on, compressed with `method`. */
export function zeroPlanes(/** @type {number} */ first, /** @type {number} */ count, method = 1) {
  const stored = packed(new Uint8Array(12 * count), method);
  const h = [...varint(first), ...varint(count), method, ...varint(12 * count)];
  const out = new Uint8Array(h.length + stored.length);
  out.set(h);
  out.set(stored, h.length);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Version 6: the compact header, body segments and records

/** An r32 (version 6): the f32's bit pattern reversed, as a minimal varint. @param {number} v */
export function r32(v) {
  const bits = new DataView(Float32Array.of(v).buffer).getUint32(0, true);
  let r = 0;
  for (let i = 0; i < 32; i++) if (bits & (2 ** i)) r += 2 ** (31 - i);
  return varint(r);
}

/**
 * A version 6 PHDR payload up to the end of its header fields (no segment), header_size counting
 * the fields given (or `size` where given, to damage it).
 * @param {{minor?: number, lossy?: boolean, coding?: number, bits?: number[], hRange?: number[], units?: number,
 *   bbox?: number[] | null, tolerance?: number, errorBound?: number, counts?: number[] | null, later?: number[], size?: number}} [h]
 * @returns {number[]}
 */
export function header6({
  minor = 0, lossy = false, coding = 0, bits = [1, 1, 1], hRange = [0, 0], units = 0, bbox = null,
  tolerance = NaN, errorBound = NaN, counts = null, later = [], size,
} = {}) {
  const flags = (lossy ? 1 : 0) | (counts ? 2 : 0) | (bbox ? 4 : 0) | (coding << 3);
  const fields = [flags, units];
  if (coding >= 2) {
    const w = (bits[0] - 1) | ((bits[1] - 1) << 5) | ((bits[2] - 1) << 10);
    fields.push(w & 0xff, w >> 8, ...r32(hRange[0]), ...r32(hRange[1]));
  }
  if (bbox) fields.push(...bbox.flatMap(r32));
  fields.push(...r32(tolerance), ...r32(errorBound));
  if (counts) fields.push(...varints(counts));
  fields.push(...later);
  return [6, minor, ...varint(size ?? fields.length), ...fields];
}

/** A record (version 6): tag, length varint32, payload. @param {number} tag @param {ArrayLike<number>} payload */
export const record = (tag, payload) => [tag, ...varint(payload.length), ...Array.from(payload)];

/**
 * A body segment (version 6): method, raw size, the records' bytes stored with the method (§6).
 * @param {number[]} raw the records, one after another @param {number} [method]
 */
export function segment(raw, method = 0) {
  const stored = packed(Uint8Array.from(raw), method);
  return [method, ...varint(raw.length), ...stored];
}

/**
 * A version 6 file: PHDR (the header, then the first segment if any), BODY chunks, other chunks
 * (given as {type, payload}) where they stand, PEND.
 * @param {number[]} header from header6
 * @param {{first?: number[] | null, chunks?: {type: string, payload: ArrayLike<number>}[], end?: number[]}} parts
 *   first: PHDR's segment; chunks: what follows PHDR, before PEND; end: PEND's payload
 */
export function file6(header, { first = null, chunks = [], end = [] } = {}) {
  return assemble5([{ type: 'PHDR', payload: [...header, ...(first ?? [])] }, ...chunks, { type: 'PEND', payload: end }]);
}

/**
 * The unit cube's six planes (h 0.5) as quantized codes at widths 2/2/1 (§7.3: ν step π/2, φ step
 * π/2, h range [0.5, 0.5]): +z, −z, +x, −x, +y, −y.
 */
export const CUBE_CODES = [[0, 0, 0], [2, 0, 0], [1, 0, 0], [1, 2, 0], [1, 1, 0], [1, 3, 0]];
/** The header fields of those codes (for header6). */
export const QUANT6 = { coding: 2, bits: [2, 2, 1], hRange: [0.5, 0.5] };

/** The codes packed at 5 bits a plane, least significant first (§2.1): 30 bits in 4 bytes. */
export function cubeBits() {
  const out = [0, 0, 0, 0];
  CUBE_CODES.forEach(([n, p, h], i) => {
    const v = n | (p << 2) | (h << 4);
    for (let b = 0; b < 5; b++) if (v & (1 << b)) out[(5 * i + b) >> 3] |= 1 << ((5 * i + b) & 7);
  });
  return out;
}

/** The cube's planes record (tag 2). */
export const planesRecord = () => record(2, [6, ...cubeBits()]);
/** An object record (tag 1): parent (+1, 0 for a root), flags, name, transform (§8, version 4's coding). */
export const objectRecord = (name = '', parent = 0, transform = /** @type {number[]} */ ([])) => {
  const n = [...Buffer.from(name)];
  return record(1, [parent, transform.length ? 1 : 0, ...varint(n.length), ...n, ...transform]);
};
/** The cube as one convex group (tag 3, kind 0) of planes 0 to 5 in `object`. */
export const cubeGroup = (object = 0) => record(3, [...varint(object), 0, ...common([0, 1, 2, 3, 4, 5])]);
/** A root object, the cube's planes and its group: 24 bytes of records. */
export const cube6Records = () => [...objectRecord(), ...planesRecord(), ...cubeGroup()];
