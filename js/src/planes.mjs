/** Plane table blocks PLNS (spec §7), version 6's planes records, and the decoding of their triplets to (ν, φ, h). */
import { fail } from './errors.mjs';
import { Cursor, unzigzag } from './varint.mjs';
import { decompress } from './compression.mjs';

const PI32 = Math.fround(Math.PI); // §7.2: the f32 nearest π, above π
const TWO_PI32 = Math.fround(2 * Math.PI);
const TWO_PI = 2 * Math.PI; // the f64 nearest 2π, below 2π

/** A growable Float64Array of triplets, grown by doubling so that appending blocks stays linear. */
export class PlaneTable {
  constructor() {
    this.data = new Float64Array(48);
    this.count = 0;
  }

  /** @param {number} n planes to append @returns {number} the index in data where they start */
  reserve(n) {
    const need = (this.count + n) * 3;
    if (need > this.data.length) {
      const grown = new Float64Array(Math.max(need, this.data.length * 2));
      grown.set(this.data.subarray(0, this.count * 3));
      this.data = grown;
    }
    const at = this.count * 3;
    this.count += n;
    return at;
  }

  /** @returns {Float64Array} exactly the planes read */
  view() {
    return this.data.subarray(0, this.count * 3);
  }
}

/**
 * Reads one PLNS payload (§7.1, or A.1's fixed head for versions 1 and 2) into the table.
 * @param {Uint8Array} payload
 * @param {import('./header.mjs').Header} header
 * @param {PlaneTable} table
 * @param {import('./compression.mjs').Limits} limits
 * @param {import('./compression.mjs').Codecs} codecs
 */
export function readPlanes(payload, header, table, limits, codecs) {
  const c = new Cursor(payload);
  let first;
  let count;
  let method;
  let rawSize;
  if (header.version[0] < 3) {
    if (payload.length < 20) fail('BAD_PAYLOAD', 'PLNS head under 20 bytes');
    first = c.u64();
    count = c.u32();
    method = c.u8();
    c.pos += 3;
    rawSize = c.u32();
  } else {
    first = c.varint();
    count = c.varint32();
    method = c.u8();
    rawSize = c.varint32();
  }
  if (first !== table.count) fail('PLANE_INDEX_MISMATCH', `block starts at ${first}, ${table.count} planes before it`);
  if (first + count > limits.planes) fail('LIMIT_EXCEEDED', `${first + count} planes`);
  checkSize(rawSize, count, header);
  const raw = decompress(method, rawSize, payload.subarray(c.pos), limits, codecs, header.version[0]);
  decodeTriplets(raw, header, table, count);
}

/**
 * Reads one planes record of version 6 (count, then the raw triplet data) into the table.
 * @param {Uint8Array} payload
 * @param {import('./header.mjs').Header} header
 * @param {PlaneTable} table
 * @param {import('./compression.mjs').Limits} limits
 */
export function readPlanesRecord(payload, header, table, limits) {
  const c = new Cursor(payload);
  const count = c.varint32();
  if (table.count + count > limits.planes) fail('LIMIT_EXCEEDED', `${table.count + count} planes`);
  checkSize(c.left, count, header);
  decodeTriplets(payload.subarray(c.pos), header, table, count);
}

/**
 * §7.1: the raw size `count` triplets of the header's coding take.
 * @param {number} rawSize @param {number} count @param {import('./header.mjs').Header} header
 */
function checkSize(rawSize, count, { coding, bits }) {
  if (coding === 3) {
    if (rawSize < 3 * count || rawSize > 15 * count) fail('SIZE_MISMATCH', `raw size ${rawSize} for ${count} planes`);
  } else {
    const size = coding === 0 ? 12 * count : coding === 1 ? 24 * count : Math.ceil((count * (bits[0] + bits[1] + bits[2])) / 8);
    if (rawSize !== size) fail('SIZE_MISMATCH', `raw size ${rawSize} for ${count} planes`);
  }
}

/**
 * @param {Uint8Array} raw @param {import('./header.mjs').Header} header @param {PlaneTable} table @param {number} count
 */
function decodeTriplets(raw, header, table, count) {
  const at = table.reserve(count);
  const out = table.data;
  const { coding } = header;
  if (coding === 0 || coding === 1) readFloats(raw, coding, count, out, at);
  else if (coding === 2) readQuantized(raw, header, count, out, at);
  else readPredicted(raw, header, count, out, at);
}

/**
 * §7.2: f32 or f64 records, range-checked in their own precision.
 * @param {Uint8Array} raw @param {number} coding @param {number} count
 * @param {Float64Array} out @param {number} at
 */
function readFloats(raw, coding, count, out, at) {
  const view = new DataView(raw.buffer, raw.byteOffset, raw.byteLength);
  const f32 = coding === 0;
  const nuMax = f32 ? PI32 : Math.PI;
  const phiEnd = f32 ? TWO_PI32 : TWO_PI;
  for (let i = 0; i < 3 * count; i += 3) {
    const nu = f32 ? view.getFloat32(4 * i, true) : view.getFloat64(8 * i, true);
    const phi = f32 ? view.getFloat32(4 * i + 4, true) : view.getFloat64(8 * i + 8, true);
    const h = f32 ? view.getFloat32(4 * i + 8, true) : view.getFloat64(8 * i + 16, true);
    if (!(nu >= 0 && nu <= nuMax && phi >= 0 && phi < phiEnd && Number.isFinite(h))) {
      fail('BAD_TRIPLET', `plane ${i / 3} of the block: (${nu}, ${phi}, ${h})`);
    }
    out[at + i] = nu;
    out[at + i + 1] = phi;
    out[at + i + 2] = h;
  }
}

/** The dequantization of §7.3, shared by codings 2 and 3. */
class Dequantizer {
  /** @param {import('./header.mjs').Header} header */
  constructor(header) {
    const [bn, bp, bh] = header.bits;
    this.mNu = 2 ** (bn - 1);
    this.nPhi = 2 ** bp;
    this.mH = 2 ** bh - 1;
    this.hMin = header.h_range[0];
    this.nuStep = Math.PI / this.mNu;
    this.phiStep = (2 * Math.PI) / this.nPhi;
    this.hStep = (header.h_range[1] - header.h_range[0]) / this.mH;
  }
}

/**
 * Bits [bit, bit + n) of a bit string, least significant first (§2.1); n ≤ 32.
 * @param {Uint8Array} raw @param {number} bit @param {number} n
 */
function bitsAt(raw, bit, n) {
  let value = 0;
  let got = 0;
  while (got < n) {
    const byte = raw[(bit + got) >>> 3];
    const shift = (bit + got) & 7;
    const take = Math.min(8 - shift, n - got);
    value += ((byte >>> shift) & ((1 << take) - 1)) * 2 ** got;
    got += take;
  }
  return value;
}

/**
 * §7.3: padding bits first (BAD_PAYLOAD), then ν codes (BAD_TRIPLET).
 * @param {Uint8Array} raw @param {import('./header.mjs').Header} header @param {number} count
 * @param {Float64Array} out @param {number} at
 */
function readQuantized(raw, header, count, out, at) {
  const [bn, bp, bh] = header.bits;
  const rec = bn + bp + bh;
  const used = count * rec;
  if (used % 8 !== 0 && raw[raw.length - 1] >>> (used % 8) !== 0) fail('BAD_PAYLOAD', 'a set padding bit');
  const q = new Dequantizer(header);
  for (let i = 0; i < count; i++) {
    const bit = i * rec;
    const qn = bitsAt(raw, bit, bn);
    if (qn > q.mNu) fail('BAD_TRIPLET', `ν code ${qn} above ${q.mNu}`);
    const qp = bitsAt(raw, bit + bn, bp);
    const qh = bitsAt(raw, bit + bn + bp, bh);
    out[at + 3 * i] = qn * q.nuStep;
    out[at + 3 * i + 1] = qp * q.phiStep;
    out[at + 3 * i + 2] = q.hMin + qh * q.hStep;
  }
}

/**
 * §7.4: three varint streams; all read, then leftovers, then magnitudes, then code ranges.
 * @param {Uint8Array} raw @param {import('./header.mjs').Header} header @param {number} count
 * @param {Float64Array} out @param {number} at
 */
function readPredicted(raw, header, count, out, at) {
  const c = new Cursor(raw);
  const v = new Float64Array(3 * count); // count ≤ raw size / 3, so bounded by the data
  for (let i = 0; i < 3 * count; i++) v[i] = c.varint();
  if (c.left > 0) fail('SIZE_MISMATCH', `${c.left} bytes after the predicted streams`);
  for (let i = 0; i < 3 * count; i++) if (v[i] >= 2 ** 33) fail('BAD_PAYLOAD', 'a predicted varint of 2^33 or more');
  const q = new Dequantizer(header);
  let a = 0;
  let b = 0;
  let h = 0;
  for (let i = 0; i < count; i++) {
    const na = a + unzigzag(v[i]);
    const sameNu = i > 0 && na === a;
    const nb = sameNu ? b + unzigzag(v[count + i]) : v[count + i];
    const nh = sameNu && nb === b ? h + unzigzag(v[2 * count + i]) : v[2 * count + i];
    if (na < 0 || na > q.mNu || nb < 0 || nb > q.nPhi - 1 || nh < 0 || nh > q.mH) {
      fail('BAD_TRIPLET', `codes (${na}, ${nb}, ${nh}) of plane ${i} out of range`);
    }
    a = na;
    b = nb;
    h = nh;
    out[at + 3 * i] = a * q.nuStep;
    out[at + 3 * i + 1] = b * q.phiStep;
    out[at + 3 * i + 2] = q.hMin + h * q.hStep;
  }
}
