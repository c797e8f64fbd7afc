/** The signature (spec §3) and chunk framing (§4.1): a walk over the chunks of a whole file. */
import { fail } from './errors.mjs';
import { crc32 } from './crc32.mjs';

const SIGNATURE = Uint8Array.of(0x89, 0x50, 0x4c, 0x4e, 0x0d, 0x0a, 0x1a, 0x0a);

/** @param {Uint8Array} bytes */
export function checkSignature(bytes) {
  const n = Math.min(bytes.length, 8);
  let prefix = true;
  for (let i = 0; i < n; i++) if (bytes[i] !== SIGNATURE[i]) prefix = false;
  if (prefix && n === 8) return;
  if (prefix) fail('TRUNCATED', 'the input ends inside the signature');
  const pln = bytes.length >= 4 && bytes[1] === 0x50 && bytes[2] === 0x4c && bytes[3] === 0x4e;
  if (pln && (bytes[0] === 0x89 || bytes[0] === 0x09)) fail('TEXT_MODE_DAMAGE', 'signature damaged as by a text-mode transfer');
  fail('BAD_SIGNATURE', 'not a .pln file');
}

/** @param {number} b */
const isLetter = (b) => (b >= 0x41 && b <= 0x5a) || (b >= 0x61 && b <= 0x7a);

/**
 * @typedef {object} Chunk
 * @property {string} type
 * @property {number} offset of the chunk's first byte
 * @property {number} head bytes of the type and the length: 8 with a u32 length, 5 to 9 with a varint
 * @property {number} length of the payload
 * @property {Uint8Array} payload a view into the input
 */

/**
 * The chunk at `pos`, framing checked in §4.1's order.
 * @param {Uint8Array} bytes
 * @param {number} pos
 * @param {number} maxLength the reader's chunk limit
 * @param {boolean} [varintLength] the length is a varint32 (a chunk after PHDR in a version 5 file), not a u32
 * @returns {Chunk}
 */
export function readChunk(bytes, pos, maxLength, varintLength = false) {
  const ends = pos === bytes.length ? 'the input ends before PEND' : 'the input ends inside a chunk head';
  if (bytes.length - pos < (varintLength ? 4 : 8)) fail('TRUNCATED', ends);
  for (let i = 0; i < 4; i++) if (!isLetter(bytes[pos + i])) fail('BAD_CHUNK_TYPE', 'a type tag that is not four ASCII letters');
  const type = String.fromCharCode(bytes[pos], bytes[pos + 1], bytes[pos + 2], bytes[pos + 3]);
  let length;
  let head;
  if (varintLength) [length, head] = lengthVarint(bytes, pos + 4);
  else {
    length = (bytes[pos + 4] | (bytes[pos + 5] << 8) | (bytes[pos + 6] << 16) | (bytes[pos + 7] << 24)) >>> 0;
    head = 8;
  }
  if (length > 0x7fffffff) fail('CHUNK_TOO_LONG', `length ${length}`);
  if (length > maxLength) fail('LIMIT_EXCEEDED', `chunk length ${length}`);
  if (bytes.length - pos - head < length + 4) fail('TRUNCATED', 'the input ends inside a payload or CRC');
  const start = pos + head;
  const end = start + length;
  const stored = (bytes[end] | (bytes[end + 1] << 8) | (bytes[end + 2] << 16) | (bytes[end + 3] << 24)) >>> 0;
  // the CRC covers the type and the payload, not the length between them
  if (crc32(bytes, start, end, crc32(bytes, pos, pos + 4)) !== stored) fail('CRC_MISMATCH', `${type} at ${pos}`);
  return { type, offset: pos, head, length, payload: bytes.subarray(start, end) };
}

/**
 * A version 5 chunk length (§4.1): a minimal varint32 of at most 5 bytes. The input ending inside
 * it is TRUNCATED; a 0x00 ending a varint of more than one byte BAD_CHUNK_LENGTH; a fifth byte with
 * bit 7 set CHUNK_TOO_LONG (no sixth byte is read). A value above 2^31 - 1 is the caller's.
 * @param {Uint8Array} bytes @param {number} at the varint's first byte
 * @returns {[number, number]} the length and the head's size (4 + the varint's bytes)
 */
function lengthVarint(bytes, at) {
  let value = 0;
  for (let i = 0; ; i++) {
    if (at + i >= bytes.length) fail('TRUNCATED', 'the input ends inside a chunk length');
    const b = bytes[at + i];
    if (i === 4 && b & 0x80) fail('CHUNK_TOO_LONG', 'a length varint of more than 5 bytes');
    value += (b & 0x7f) * 2 ** (7 * i);
    if (!(b & 0x80)) {
      if (i > 0 && b === 0) fail('BAD_CHUNK_LENGTH', 'a length varint that is not minimal');
      return [value, 5 + i];
    }
  }
}
