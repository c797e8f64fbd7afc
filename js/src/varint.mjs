/**
 * A cursor over a payload: fixed-size little-endian fields (spec §2.1) and varints (§2.2).
 * Every read past the end is BAD_PAYLOAD, the code the spec gives a payload or body that ends
 * inside a field, wherever it is.
 */
import { fail } from './errors.mjs';

/** Values at or above 2^53 are not exact in a Number; every varint above 2^53 reads as this,
 * which is above every bound the format sets (2^52 grid coordinates, 2^33 predicted codes). */
const VARINT_SATURATED = 2 ** 53 + 2;

const TWO49 = 2 ** 49;

export class Cursor {
  /**
   * @param {Uint8Array} bytes
   * @param {number} [start]
   * @param {number} [end]
   */
  constructor(bytes, start = 0, end = bytes.length) {
    this.bytes = bytes;
    this.view = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
    this.pos = start;
    this.end = end;
  }

  /** @returns {number} bytes not read yet */
  get left() {
    return this.end - this.pos;
  }

  /** @param {number} n */
  need(n) {
    if (this.end - this.pos < n) fail('BAD_PAYLOAD', `ends inside a field of ${n} bytes`);
  }

  u8() {
    this.need(1);
    return this.bytes[this.pos++];
  }

  u16() {
    this.need(2);
    const v = this.view.getUint16(this.pos, true);
    this.pos += 2;
    return v;
  }

  u32() {
    this.need(4);
    const v = this.view.getUint32(this.pos, true);
    this.pos += 4;
    return v;
  }

  /** u64 as a Number: exact below 2^53, which every offset and count this reader accepts is. */
  u64() {
    this.need(8);
    const lo = this.view.getUint32(this.pos, true);
    const hi = this.view.getUint32(this.pos + 4, true);
    this.pos += 8;
    return hi * 4294967296 + lo;
  }

  f32() {
    this.need(4);
    const v = this.view.getFloat32(this.pos, true);
    this.pos += 4;
    return v;
  }

  f64() {
    this.need(8);
    const v = this.view.getFloat64(this.pos, true);
    this.pos += 8;
    return v;
  }

  /** @param {number} n @returns {Uint8Array} a view, not a copy */
  take(n) {
    this.need(n);
    const v = this.bytes.subarray(this.pos, this.pos + n);
    this.pos += n;
    return v;
  }

  /**
   * A minimal LEB128 varint below 2^64 (§2.2), exact below 2^53 and VARINT_SATURATED above it.
   * @returns {number}
   */
  varint() {
    const b = this.bytes;
    let pos = this.pos;
    const end = this.end;
    if (pos < end && b[pos] < 0x80) {
      this.pos = pos + 1;
      return b[pos];
    }
    // lo: bits 0-48 (seven groups, exact), hi: the rest
    let lo = 0;
    let hi = 0;
    let mul = 1;
    for (let i = 0; ; i++) {
      if (pos >= end) fail('BAD_PAYLOAD', 'the data ends inside a varint');
      const byte = b[pos++];
      if (i === 9 && byte > 1) fail('BAD_PAYLOAD', 'a varint of 2^64 or more');
      if (i < 7) lo += (byte & 0x7f) * mul;
      else hi += (byte & 0x7f) * (mul / TWO49);
      if (byte < 0x80) {
        if (byte === 0 && i > 0) fail('BAD_PAYLOAD', 'a varint that is not minimal');
        this.pos = pos;
        if (hi < 16) return lo + hi * TWO49;
        return hi === 16 && lo === 0 ? 2 ** 53 : VARINT_SATURATED;
      }
      mul *= 128;
    }
  }

  /** A varint below 2^32 (§2.2). */
  varint32() {
    const v = this.varint();
    if (v >= 4294967296) fail('BAD_PAYLOAD', 'a varint32 of 2^32 or more');
    return v;
  }
}

/**
 * Zigzag decoding (§2.2): 0, 1, 2, 3 ... to 0, -1, 1, -2 ...; arithmetic, not bit operations,
 * because values reach 2^53.
 * @param {number} v
 */
export function unzigzag(v) {
  return v % 2 === 0 ? v / 2 : -(v + 1) / 2;
}

/**
 * A bit string of n bits (§2.1), checked for set padding bits, unpacked to bytes 0/1.
 * @param {Cursor} b @param {number} n
 */
export function readBits(b, n) {
  const packed = b.take(Math.ceil(n / 8));
  if (n % 8 !== 0 && packed[packed.length - 1] >>> (n % 8) !== 0) fail('BAD_PAYLOAD', 'a set padding bit');
  const bits = new Uint8Array(n);
  for (let i = 0; i < n; i++) bits[i] = (packed[i >>> 3] >>> (i & 7)) & 1;
  return bits;
}
