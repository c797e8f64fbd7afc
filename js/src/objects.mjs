/** Objects OBJT (spec §8, A.1 for versions 1 and 2). */
import { fail } from './errors.mjs';
import { Cursor } from './varint.mjs';

const utf8 = new TextDecoder('utf-8', { fatal: true, ignoreBOM: true });

/**
 * @typedef {object} PlnObject
 * @property {string} name
 * @property {number | null} parent the parent's index, null for a root
 * @property {number[] | null} transform 16 entries row by row, or null
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
    index = c.varint32();
    const p = c.varint32();
    parent = p === 0 ? null : p - 1;
    flags = c.u8();
    nameLength = c.varint();
    if (nameLength > 65535) fail('BAD_OBJECT', `name of ${nameLength} bytes`);
  }
  const nameBytes = c.take(nameLength);
  let transform = null;
  if (flags & 1) {
    transform = [];
    for (let i = 0; i < 16; i++) transform.push(c.f64());
  }
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
    if (transform[12] !== 0 || transform[13] !== 0 || transform[14] !== 0 || transform[15] !== 1) {
      fail('BAD_OBJECT', 'transform last row not 0 0 0 1');
    }
  }
  return { name, parent, transform, groups: [] };
}
