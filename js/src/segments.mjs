/**
 * Version 6's body segments and records: a segment (in PHDR's tail or a BODY chunk) is a
 * compression method, a raw size and data compressed per §6; its raw bytes are whole records, each
 * a tag, a length and a payload. One segment is decompressed and read at a time.
 */
import { fail, PlnError } from './errors.mjs';
import { Cursor } from './varint.mjs';
import { decompress } from './compression.mjs';

/** The chunk type whose payload each record tag carries in versions 1 to 5. @type {Record<number, string>} */
export const RECORDS = { 1: 'OBJT', 2: 'PLNS', 3: 'GRUP', 4: 'cOLR', 5: 'mETA' };

/**
 * The raw bytes of one body segment (§6's checks and limits).
 * @param {Uint8Array} stored the segment: method u8, raw_size varint32, data
 * @param {import('./compression.mjs').Limits} limits
 * @param {import('./compression.mjs').Codecs} codecs
 * @returns {Uint8Array}
 */
export function segmentBytes(stored, limits, codecs) {
  const c = new Cursor(stored);
  const method = c.u8();
  const rawSize = c.varint32();
  return decompress(method, rawSize, stored.subarray(c.pos), limits, codecs, 6);
}

/**
 * Calls `each` on every record of a segment's raw bytes, in order. A record that does not fit in
 * what is left of the segment is BAD_PAYLOAD; an error names the record and its offset in the raw
 * bytes (the caller names the chunk).
 * @param {Uint8Array} raw
 * @param {(tag: number, payload: Uint8Array, at: number, size: number) => void} each at: the record's offset in
 *   raw; size: its bytes there, tag and length included
 */
export function forEachRecord(raw, each) {
  const c = new Cursor(raw);
  while (c.left > 0) {
    const at = c.pos;
    let tag = -1;
    try {
      tag = c.u8();
      const length = c.varint32();
      if (length > c.left) fail('BAD_PAYLOAD', `a record of ${length} bytes, ${c.left} left in the segment`);
      const size = c.pos + length - at;
      each(tag, c.take(length), at, size);
    } catch (err) {
      if (err instanceof PlnError && !err.record) {
        err.record = { tag, offset: at };
        err.message += ` (record of tag ${tag} at byte ${at} of the segment's raw bytes)`;
      }
      throw err;
    }
  }
}
