/** Objects OBJT and version 6's object records (spec §8; Appendix A for versions 1 to 3: fixed heads in 1 and 2, 16 × f64 transforms). */
import { fail } from './errors.mjs';
import { Cursor } from './varint.mjs';

const utf8 = new TextDecoder('utf-8', { fatal: true, ignoreBOM: true });

/**
 * @typedef {object} PlnObject
 * @property {string} name
 * @property {number | null} parent the parent's index, null for a root
 * @property {number[] | null} transform 16 entries row by row (version 4: its last row 0 0 0 1), or null
 * @property {import('./groups.mjs').Group[]} groups
 */

/**
 * @param {Uint8Array} payload
 * @param {number} major
 * @param {number} before objects read before this one
 * @param {import('./compression.mjs').Limits} limits
 * @returns {PlnObject}
 */
export function readObject(payload, major, before, limits) {
  if (before + 1 > limits.objects) fail('LIMIT_EXCEEDED', `more than ${limits.objects} objects`);
  const c = new Cursor(payload);
  let index;
  let parent;
  let flags;
  let nameLength;
  if (major < 3) {
    index = c.u32();
    const p = c.u32();
    parent = p === 0xffffffff ? null : p;
    flags = c.u8();
    c.u8();
    nameLength = c.u16();
  } else {
    // version 6: an object's index is its position among the object records
    index = major >= 6 ? before : c.varint32();
    const p = c.varint32();
    parent = p === 0 ? null : p - 1;
    flags = c.u8();
    nameLength = c.varint();
    if (nameLength > 65535) fail('BAD_OBJECT', `name of ${nameLength} bytes`);
  }
  const nameBytes = c.take(nameLength);
  let transform = null;
  if (flags & 1) transform = major >= 4 ? readCodedTransform(c) : readFullTransform(c);
  if (index !== before) fail('BAD_OBJECT', `index ${index}, expected ${before}`);
  if (parent !== null && parent >= before) fail('BAD_OBJECT', `parent ${parent} not an earlier object`);
  let name;
  try {
    name = utf8.decode(nameBytes);
  } catch {
    fail('BAD_OBJECT', 'name not UTF-8');
  }
  if (transform) {
    if (transform.some((v) => !Number.isFinite(v))) fail('BAD_OBJECT', 'a non-finite transform entry');
    if (major < 4 && (transform[12] !== 0 || transform[13] !== 0 || transform[14] !== 0 || transform[15] !== 1)) {
      fail('BAD_OBJECT', 'transform last row not 0 0 0 1');
    }
  }
  return { name, parent, transform, groups: [] };
}

/**
 * Versions 1 to 3 (Appendix A): M as 16 × f64, row by row.
 * @param {Cursor} c
 */
function readFullTransform(c) {
  const m = [];
  for (let i = 0; i < 16; i++) m.push(c.f64());
  return m;
}

/**
 * Version 4 (§8): three bytes of twelve 2-bit codes for the entries of M's first three rows, row by
 * row (entry i's code is bits 2i and 2i + 1 of the bit string, least significant first: 0 is +0.0,
 * 1 is 1.0, 2 an f32, 3 an f64), then the values of codes 2 and 3 in entry order; the last row is
 * 0 0 0 1. Twelve codes fill the 24 bits, so there are no padding bits.
 * @param {Cursor} c
 */
function readCodedTransform(c) {
  const b = c.take(3);
  const codes = b[0] | (b[1] << 8) | (b[2] << 16);
  const m = [];
  for (let i = 0; i < 12; i++) {
    const code = (codes >>> (2 * i)) & 3;
    m.push(code === 0 ? 0 : code === 1 ? 1 : code === 2 ? c.f32() : c.f64());
  }
  m.push(0, 0, 0, 1);
  return m;
}
