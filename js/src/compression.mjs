/**
 * Compressed payloads (spec §6): method 1 (zlib) and, from version 4, method 2 (Brotli). The
 * decompressors are injected so that this module runs in a browser as well as in Node: see
 * InflateFn and BrotliFn.
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
 * A decompressor of one Brotli stream (RFC 7932), with InflateFn's contract: output never longer
 * than maxOutputLength, `consumed` the input bytes up to the stream's end where it can tell (bytes
 * after it are BAD_COMPRESSION for Brotli, §6 step 6), an Error with `truncated` where the input
 * ends inside the stream, `tooLong` where the output would pass maxOutputLength, any other Error
 * for an invalid stream.
 * @typedef {InflateFn} BrotliFn
 */

/**
 * The decompressors a reader was given; null where it has none (such payloads are then
 * BAD_COMPRESSION).
 * @typedef {{inflate: InflateFn | null, brotli: BrotliFn | null}} Codecs
 */

/**
 * @typedef {object} Limits
 * @property {number} chunkLength  §4.1 step 4
 * @property {number} rawSize      §6 step 2
 * @property {number} ratio        §6 step 4
 * @property {number} planes       §7.1 step 3
 * @property {number} refs         §9.2 step 2
 * @property {number} objects      §8 step 1
 * @property {number} triangles    the output of a whole decode, §12.4
 * @property {number} vertices     the same
 */

/**
 * planefmt's defaults (§12.4): like Pillow's MAX_IMAGE_PIXELS they keep one decode within a few
 * hundred MB; a caller raises them for larger meshes.
 * @type {Limits}
 */
export const DEFAULT_LIMITS = Object.freeze({
  chunkLength: 256 * 1024 * 1024,
  rawSize: 256 * 1024 * 1024,
  ratio: 1100,
  planes: 2 ** 22,
  refs: 2 ** 24,
  objects: 2 ** 24,
  triangles: 2 ** 22,
  vertices: 2 ** 22,
});

/** The stream of each compressed method, for messages. */
const NAMES = ['', 'zlib', 'Brotli'];

/**
 * The raw bytes of a payload stored with `method` (§6, checks in its order).
 * @param {number} method
 * @param {number} rawSize
 * @param {Uint8Array} stored
 * @param {Limits} limits
 * @param {Codecs} codecs
 * @param {number} major the file's major version: method 2 exists from version 4 (Appendix A)
 * @returns {Uint8Array}
 */
export function decompress(method, rawSize, stored, limits, codecs, major) {
  if (method !== 0 && method !== 1 && !(method === 2 && major >= 4)) fail('BAD_COMPRESSION', `method ${method} in a version ${major} file`);
  if (rawSize > limits.rawSize) fail('LIMIT_EXCEEDED', `raw size ${rawSize}`);
  if (method === 0) {
    if (stored.length !== rawSize) fail('SIZE_MISMATCH', `${stored.length} stored bytes, raw size ${rawSize}`);
    return stored;
  }
  if (rawSize > limits.ratio * stored.length) fail('LIMIT_EXCEEDED', `raw size ${rawSize} from ${stored.length} bytes`);
  const name = NAMES[method];
  const fn = method === 1 ? codecs.inflate : codecs.brotli;
  if (!fn) fail('BAD_COMPRESSION', `no ${name} decompressor given for a compressed payload`);
  let result;
  try {
    result = fn(stored, rawSize + 1);
  } catch (err) {
    if (err instanceof PlnError) throw err;
    if (/** @type {any} */ (err).truncated) fail('SIZE_MISMATCH', `the stored bytes end inside the ${name} stream`);
    if (/** @type {any} */ (err).tooLong) fail('SIZE_MISMATCH', `the ${name} stream decompresses beyond raw size`);
    fail('BAD_COMPRESSION', `${name}: ${String(/** @type {any} */ (err).message ?? err)}`);
  }
  const output = result instanceof Uint8Array ? result : result.output;
  const consumed = result instanceof Uint8Array ? undefined : result.consumed;
  // an output that passed raw size was cut short there: where its stream ends is unknown
  if (output.length > rawSize) fail('SIZE_MISMATCH', `the ${name} stream decompresses beyond raw size ${rawSize}`);
  // Brotli: bytes after the stream are an invalid stream (§6 step 6), before the output's size
  if (method === 2 && consumed !== undefined && consumed !== stored.length) {
    fail('BAD_COMPRESSION', `${stored.length - consumed} stored bytes after the Brotli stream`);
  }
  if (output.length !== rawSize) fail('SIZE_MISMATCH', `decompressed to ${output.length} bytes, raw size ${rawSize}`);
  if (consumed !== undefined && consumed !== stored.length) fail('SIZE_MISMATCH', 'stored bytes after the zlib stream');
  return output;
}
