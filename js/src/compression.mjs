/**
 * Compressed payloads (spec §6). The zlib inflater is injected so that this module runs in a
 * browser as well as in Node: see InflateFn.
 */
import { fail, PlnError } from './errors.mjs';

/**
 * An inflater of one zlib stream (RFC 1950). It returns the output, never longer than
 * maxOutputLength (it throws or stops there), and, where it can tell, how many input bytes the
 * stream took (without that, stored bytes after the stream's end go unnoticed). It throws an
 * Error whose `truncated` property is true where the input ends inside the stream, and any other
 * Error for corrupt data.
 * @typedef {(stored: Uint8Array, maxOutputLength: number) => (Uint8Array | {output: Uint8Array, consumed?: number})} InflateFn
 */

/**
 * @typedef {object} Limits
 * @property {number} chunkLength  §4.1 step 4
 * @property {number} rawSize      §6 step 2
 * @property {number} ratio        §6 step 4
 * @property {number} planes       §7.1 step 3
 * @property {number} refs         §9.2 step 2
 * @property {number} objects      §8 step 1
 */

/** planefmt's defaults (§12.4). @type {Limits} */
export const DEFAULT_LIMITS = Object.freeze({
  chunkLength: 256 * 1024 * 1024,
  rawSize: 256 * 1024 * 1024,
  ratio: 1100,
  planes: 2 ** 28,
  refs: 2 ** 24,
  objects: 2 ** 24,
});

/**
 * The raw bytes of a payload stored with `method` (§6, checks in its order).
 * @param {number} method
 * @param {number} rawSize
 * @param {Uint8Array} stored
 * @param {Limits} limits
 * @param {InflateFn | null} inflate
 * @returns {Uint8Array}
 */
export function decompress(method, rawSize, stored, limits, inflate) {
  if (method !== 0 && method !== 1) fail('BAD_COMPRESSION', `method ${method}`);
  if (rawSize > limits.rawSize) fail('LIMIT_EXCEEDED', `raw size ${rawSize}`);
  if (method === 0) {
    if (stored.length !== rawSize) fail('SIZE_MISMATCH', `${stored.length} stored bytes, raw size ${rawSize}`);
    return stored;
  }
  if (rawSize > limits.ratio * stored.length) fail('LIMIT_EXCEEDED', `raw size ${rawSize} from ${stored.length} bytes`);
  if (!inflate) fail('BAD_COMPRESSION', 'no inflater given for a compressed payload');
  let result;
  try {
    result = inflate(stored, rawSize + 1);
  } catch (err) {
    if (err instanceof PlnError) throw err;
    if (/** @type {any} */ (err).truncated) fail('SIZE_MISMATCH', 'the stored bytes end inside the zlib stream');
    if (/** @type {any} */ (err).tooLong) fail('SIZE_MISMATCH', 'the stream inflates beyond raw size');
    fail('BAD_COMPRESSION', String(/** @type {any} */ (err).message ?? err));
  }
  const output = result instanceof Uint8Array ? result : result.output;
  const consumed = result instanceof Uint8Array ? undefined : result.consumed;
  if (output.length !== rawSize) fail('SIZE_MISMATCH', `inflated to ${output.length} bytes, raw size ${rawSize}`);
  if (consumed !== undefined && consumed !== stored.length) fail('SIZE_MISMATCH', 'stored bytes after the zlib stream');
  return output;
}
