/** The header chunk PHDR: spec §5 (versions 5 and 6), A.5 (versions 3 and 4) and A.1 (versions 1 and 2). */
import { fail } from './errors.mjs';
import { Cursor } from './varint.mjs';

/**
 * @typedef {object} Header
 * @property {[number, number]} version
 * @property {boolean} lossy
 * @property {number} coding 0 float32, 1 float64, 2 quantized, 3 predicted
 * @property {[number, number, number]} bits widths as stored for codings 2 and 3, else [0, 0, 0]
 * @property {[number, number]} h_range [h_min, h_max] for codings 2 and 3, else [0, 0]
 * @property {number} units the length unit, 0-7 (version 5: bits 0-3 of the units byte)
 * @property {'Y' | 'Z' | null} up_axis version 5: bits 4-5 of the units byte (§5); null where not said and before version 5
 * @property {[[number, number, number], [number, number, number]] | null} bbox
 * @property {number} tolerance NaN if none
 * @property {number} error_bound NaN if not measured
 * @property {{planes: number, objects: number, groups: number} | null} counts
 */

/**
 * The header, and in version 6 the bytes after its fields: the file's first body segment (§3 of
 * version 6), empty where there is none.
 * @param {Uint8Array} payload
 * @returns {{header: Header, segment: Uint8Array}}
 */
export function parseHeader(payload) {
  if (payload.length < 2) fail('BAD_PAYLOAD', 'PHDR under 2 bytes');
  const major = payload[0];
  if (major < 1 || major > 6) fail('UNSUPPORTED_VERSION', `major version ${major}`);
  if (major === 6) return parseHeader6(payload);
  return { header: parseFixed(payload), segment: payload.subarray(payload.length) };
}

/**
 * Versions 1 to 5: a fixed part, then the fields the flags and the coding call for.
 * @param {Uint8Array} payload
 * @returns {Header}
 */
function parseFixed(payload) {
  const c = new Cursor(payload);
  const major = payload[0];
  const minor = payload[1];
  const old = major < 3;
  const v5 = major === 5;
  // the fixed part: 8 bytes in version 5 (flags a u8), 9 in 3 and 4 (flags a u16), 108 in 1 and 2
  if (payload.length < (old ? 108 : v5 ? 8 : 9)) fail('BAD_PAYLOAD', 'PHDR too short');
  c.pos = 2;
  const flags = v5 ? c.u8() : c.u16();
  const coding = c.u8();
  // version 1 has no predicted coding (A.1); 2 to 4 have it
  if (coding > (major === 1 ? 2 : 3)) fail('UNSUPPORTED_CODING', `coding ${coding}`);
  const quantized = coding >= 2;
  const bits = /** @type {[number, number, number]} */ ([c.u8(), c.u8(), c.u8()]);
  const unitsByte = c.u8();
  // version 5: the unit in bits 0-3, the up axis in bits 4-5, bits 6-7 ignored (§5, §2.1)
  const units = v5 ? unitsByte & 0x0f : unitsByte;
  const up = v5 ? (unitsByte >> 4) & 3 : 0;
  let hMin = 0;
  let hMax = 0;
  let bbox = null;
  let tolerance;
  let errorBound;
  let counts = null;
  const bboxKnown = (flags & 4) !== 0;
  const countsKnown = (flags & 2) !== 0;
  if (old) {
    c.pos = 12;
    const h0 = c.f64();
    const h1 = c.f64();
    if (quantized) [hMin, hMax] = [h0, h1];
    const box = [c.f64(), c.f64(), c.f64(), c.f64(), c.f64(), c.f64()];
    if (bboxKnown) bbox = box;
    tolerance = c.f64();
    errorBound = c.f64();
    const planes = c.u64();
    const objects = c.u32();
    const groups = c.u32();
    if (countsKnown) counts = { planes, objects, groups };
  } else {
    if (quantized) {
      hMin = c.f64();
      hMax = c.f64();
    }
    if (bboxKnown) bbox = [c.f32(), c.f32(), c.f32(), c.f32(), c.f32(), c.f32()];
    tolerance = c.f32();
    errorBound = c.f32();
    if (countsKnown) counts = { planes: c.varint(), objects: c.varint32(), groups: c.varint32() };
  }
  return checked({
    version: [major, minor],
    lossy: (flags & 1) !== 0,
    coding,
    bits: quantized ? bits : [0, 0, 0],
    h_range: [hMin, hMax],
    units,
    up_axis: up === 1 ? 'Y' : up === 2 ? 'Z' : null,
    bbox: bbox && [[bbox[0], bbox[1], bbox[2]], [bbox[3], bbox[4], bbox[5]]],
    tolerance,
    error_bound: errorBound,
    counts,
  }, up);
}

/**
 * Version 6: header_size, then flags (the coding in bits 3-4), units, the widths as a u16 and every
 * value as an r32; fields past those the flags call for, up to header_size, are a newer minor's.
 * @param {Uint8Array} payload
 * @returns {{header: Header, segment: Uint8Array}}
 */
function parseHeader6(payload) {
  const c = new Cursor(payload, 2);
  const size = c.varint32();
  if (size > c.left) fail('BAD_PAYLOAD', `header_size ${size}, ${c.left} bytes left in PHDR`);
  const end = c.pos + size;
  // reads past header_size end inside the header: a header_size below what the flags call for
  const h = new Cursor(payload, c.pos, end);
  const flags = h.u8();
  const unitsByte = h.u8();
  const coding = (flags >> 3) & 3;
  const quantized = coding >= 2;
  /** @type {[number, number, number]} */
  let bits = [0, 0, 0];
  let hMin = 0;
  let hMax = 0;
  if (quantized) {
    const w = h.u16();
    bits = [(w & 31) + 1, ((w >> 5) & 31) + 1, ((w >> 10) & 31) + 1];
    hMin = r32(h);
    hMax = r32(h);
  }
  let bbox = null;
  if (flags & 4) bbox = [r32(h), r32(h), r32(h), r32(h), r32(h), r32(h)];
  const tolerance = r32(h);
  const errorBound = r32(h);
  const counts = flags & 2 ? { planes: h.varint(), objects: h.varint32(), groups: h.varint32() } : null;
  const up = (unitsByte >> 4) & 3;
  const header = checked({
    version: [6, payload[1]],
    lossy: (flags & 1) !== 0,
    coding,
    bits,
    h_range: [hMin, hMax],
    units: unitsByte & 0x0f,
    up_axis: up === 1 ? 'Y' : up === 2 ? 'Z' : null,
    bbox: bbox && [[bbox[0], bbox[1], bbox[2]], [bbox[3], bbox[4], bbox[5]]],
    tolerance,
    error_bound: errorBound,
    counts,
  }, up);
  return { header, segment: payload.subarray(end) };
}

const R32 = new DataView(new ArrayBuffer(4));

/**
 * An r32 (version 6): an f32's bit pattern, its 32 bits reversed, as a varint32; so that values with
 * few mantissa bits (0, 1, 0.5, a rounded tolerance) take one to three bytes.
 * @param {Cursor} c
 */
function r32(c) {
  let x = c.varint32();
  x = ((x >>> 1) & 0x55555555) | ((x & 0x55555555) << 1);
  x = ((x >>> 2) & 0x33333333) | ((x & 0x33333333) << 2);
  x = ((x >>> 4) & 0x0f0f0f0f) | ((x & 0x0f0f0f0f) << 4);
  x = ((x >>> 8) & 0x00ff00ff) | ((x & 0x00ff00ff) << 8);
  R32.setUint32(0, ((x >>> 16) | (x << 16)) >>> 0);
  return R32.getFloat32(0);
}

/**
 * §5's value checks 6 to 9, on a header read.
 * @param {Header} header @param {number} up the up axis bits as stored
 * @returns {Header}
 */
function checked(header, up) {
  const { coding, bits, h_range: [hMin, hMax], units, tolerance, error_bound: errorBound } = header;
  const bbox = header.bbox && [...header.bbox[0], ...header.bbox[1]];
  if (coding >= 2) {
    if (bits.some((b) => b < 1 || b > 32)) fail('UNSUPPORTED_CODING', `widths ${bits}`);
    // a width that overflows binary64 would make every dequantized h infinite (§5, §7.3)
    if (!Number.isFinite(hMin) || !Number.isFinite(hMax) || !Number.isFinite(hMax - hMin) || hMin > hMax) {
      fail('BAD_HEADER_VALUE', 'h range');
    }
  }
  if (units > 7) fail('BAD_HEADER_VALUE', `units ${units}`);
  if (up === 3) fail('BAD_HEADER_VALUE', 'up axis 3');
  if (bbox && (bbox.some((v) => !Number.isFinite(v)) || bbox[0] > bbox[3] || bbox[1] > bbox[4] || bbox[2] > bbox[5])) {
    fail('BAD_HEADER_VALUE', 'bounding box');
  }
  for (const v of [tolerance, errorBound]) {
    if (!Number.isNaN(v) && !(Number.isFinite(v) && v >= 0)) fail('BAD_HEADER_VALUE', 'tolerance or error bound');
  }
  return header;
}
