/** Ancillary chunks: colours cOLR (spec §10.1), index iNDX (§10.2; version 6's too), metadata mETA (§10.3). */
import { fail } from './errors.mjs';
import { Cursor } from './varint.mjs';

const utf8 = new TextDecoder('utf-8', { fatal: true, ignoreBOM: true });

/** Values of the keywords §10.3 defines. @type {Record<string, string[]>} */
const KEYWORDS = { up_axis: ['Y', 'Z'] };

/**
 * @param {Uint8Array} payload
 * @param {import('./groups.mjs').Group[]} groups read so far
 * @param {number} major the file's major version: from 4, a 12-byte payload is one colour for all; in 6,
 *   group and count are varint32s and 4 bytes after them one colour for all
 * @returns {{group: number, rgba: Uint8Array}} 4 bytes per reference (a single colour repeated)
 */
export function readColours(payload, groups, major) {
  const c = new Cursor(payload);
  const v6 = major >= 6;
  const group = v6 ? c.varint32() : c.u32();
  const count = v6 ? c.varint32() : c.u32();
  const uniform = v6 ? c.left === 4 : major >= 4 && payload.length === 12;
  // version 6: a copy, not a view, so that the segment it came from is not held (one segment at a time)
  const colours = v6 ? c.take(uniform ? 4 : 4 * count).slice() : c.take(uniform ? 4 : 4 * count);
  if (c.left > 0) fail('BAD_COLOURS', `${c.left} bytes after the colours`);
  if (group >= groups.length) fail('BAD_COLOURS', `group ${group} not read yet`);
  if (count !== groups[group].refs.length) fail('BAD_COLOURS', `${count} colours for ${groups[group].refs.length} references`);
  // a group without references (version 5, §9.2) takes one colour for all its triangles
  if (count === 0 && !uniform) fail('BAD_COLOURS', 'a count of 0 without its one colour');
  const size = 4 * Math.max(count, 1);
  /** @type {Uint8Array | null} */
  let rgba = null;
  return {
    group,
    // Expanded on first use, now that count is the group's ref_count (within the reader's limit): a
    // later cOLR of the group replaces this one (§10.1), so a file of many one-colour chunks for a
    // large group costs one expansion, not one per chunk (fuzz/hostile.py x_colour_expansion).
    get rgba() {
      if (rgba === null) {
        rgba = new Uint8Array(size);
        rgba.set(colours);
        if (uniform) for (let n = 4; n < size; n *= 2) rgba.copyWithin(n, 0, Math.min(n, size - n));
      }
      return rgba;
    },
  };
}

/**
 * Checks an iNDX payload against the chunks read before it.
 * @param {Uint8Array} payload
 * @param {number} offset of the iNDX chunk
 * @param {number} firstAfterHeader offset of the chunk after PHDR
 * @param {{offset: number, type: string, ordinal: number}[]} listed the OBJT, PLNS and GRUP chunks read
 */
export function checkIndex(payload, offset, firstAfterHeader, listed) {
  const c = new Cursor(payload);
  const count = c.u32();
  c.need(16 * count);
  if (c.left > 16 * count) fail('BAD_INDEX', `${c.left - 16 * count} bytes after the entries`);
  if (count !== listed.length) fail('BAD_INDEX', `${count} entries for ${listed.length} chunks`);
  let last = -1;
  for (let i = 0; i < count; i++) {
    const at = c.u64();
    const type = String.fromCharCode(...c.take(4));
    const ordinal = c.u32();
    if (at < firstAfterHeader || at >= offset || at <= last) fail('BAD_INDEX', `entry ${i}: offset ${at}`);
    last = at;
    const want = listed[i];
    if (at !== want.offset || type !== want.type || ordinal !== want.ordinal) fail('BAD_INDEX', `entry ${i} does not match the file`);
  }
}

/**
 * Checks a version 6 iNDX payload against the records read before it: count, then per record of an
 * object, planes or group its chunk's offset (a difference from the entry before), its offset in
 * that segment's raw bytes, its tag and its ordinal.
 * @param {Uint8Array} payload
 * @param {number} offset of the iNDX chunk
 * @param {{offset: number, raw: number, type: string, ordinal: number}[]} listed the records read
 */
export function checkIndex6(payload, offset, listed) {
  const c = new Cursor(payload);
  const count = c.varint();
  // an entry takes 4 bytes at least: more entries than that end inside the payload
  if (count > c.left / 4) fail('BAD_PAYLOAD', `${count} entries in ${c.left} bytes`);
  const entries = [];
  let at = 0;
  for (let i = 0; i < count; i++) {
    at += c.varint();
    entries.push({ at, raw: c.varint(), tag: c.u8(), ordinal: c.varint() });
  }
  if (c.left > 0) fail('BAD_INDEX', `${c.left} bytes after the entries`);
  if (count !== listed.length) fail('BAD_INDEX', `${count} entries for ${listed.length} records`);
  entries.forEach(({ at: chunk, raw, tag, ordinal }, i) => {
    if (chunk < 8 || chunk >= offset) fail('BAD_INDEX', `entry ${i}: chunk offset ${chunk}`);
    const want = listed[i];
    if (chunk !== want.offset || raw !== want.raw || RECORD_TYPES[tag] !== want.type || ordinal !== want.ordinal) {
      fail('BAD_INDEX', `entry ${i} does not match the file`);
    }
  });
}

/** The records an iNDX of version 6 lists, by tag. @type {Record<number, string>} */
const RECORD_TYPES = { 1: 'OBJT', 2: 'PLNS', 3: 'GRUP' };

/**
 * @param {Uint8Array} payload
 * @param {Record<string, string>} metadata read so far; the new keyword is added
 * @param {number} major the file's major version: in version 5 the up axis is the header's, not a keyword's
 */
export function readMetadata(payload, metadata, major) {
  const zero = payload.indexOf(0);
  if (zero < 0) fail('BAD_METADATA', 'no 0x00 separator');
  if (zero < 1 || zero > 79) fail('BAD_METADATA', `keyword of ${zero} bytes`);
  for (let i = 0; i < zero; i++) if (payload[i] < 0x21 || payload[i] > 0x7e) fail('BAD_METADATA', 'keyword not printable ASCII');
  const keyword = String.fromCharCode(...payload.subarray(0, zero));
  let value;
  try {
    value = utf8.decode(payload.subarray(zero + 1));
  } catch {
    fail('BAD_METADATA', 'value not UTF-8');
  }
  if (major >= 5 && keyword === 'up_axis') fail('BAD_METADATA', 'up_axis in a version 5 file (the header holds it, §5)');
  if (Object.hasOwn(metadata, keyword)) fail('BAD_METADATA', `keyword ${keyword} twice`);
  if (Object.hasOwn(KEYWORDS, keyword) && !KEYWORDS[keyword].includes(value)) fail('BAD_METADATA', `${keyword} = ${value}`);
  metadata[keyword] = value;
}
