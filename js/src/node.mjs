/**
 * The Node entry: readPln with Node's zlib as its inflater and its Brotli decoder (the one module
 * here importing Node).
 */
import zlib from 'node:zlib';
import { readPln as readPlnCore, PlnError } from './index.mjs';

export { PlnError };

/**
 * Options that hold node:zlib's synchronous decompressors to maxOutputLength bytes of output in
 * all (spec §6: at most raw size + 1). Node writes at most chunkSize bytes a step and throws
 * ERR_BUFFER_TOO_LARGE once its output passes maxOutputLength; with one chunk of maxOutputLength
 * bytes and a limit one below, a stream that would go on is stopped after its first chunk. (Node's
 * smallest chunk is 64 bytes: under that, at most 64 bytes.)
 * @param {number} maxOutputLength
 */
function bounded(maxOutputLength) {
  return { info: true, chunkSize: Math.max(64, maxOutputLength), maxOutputLength: Math.max(1, maxOutputLength - 1) };
}

/**
 * @param {any} err an error of node:zlib
 * @returns {never}
 */
function rethrow(err) {
  // the input ended inside the stream: "unexpected end of file", for zlib and Brotli alike
  if (err.code === 'Z_BUF_ERROR') err.truncated = true;
  if (err.code === 'ERR_BUFFER_TOO_LARGE') err.tooLong = true;
  // Brotli's decoder failing to allocate its buffers: a limit of this reader, not a corrupt stream
  if (typeof err.code === 'string' && err.code.startsWith('ERR__ERROR_ALLOC')) throw new PlnError('LIMIT_EXCEEDED', err.message);
  throw err;
}

/**
 * @param {{buffer: Buffer, engine: {bytesWritten: number}}} result
 * @returns {{output: Uint8Array, consumed: number}}
 */
function unpack({ buffer, engine }) {
  // the engine's bytesWritten is the input the stream took, to find bytes after its end
  return { output: new Uint8Array(buffer.buffer, buffer.byteOffset, buffer.length), consumed: engine.bytesWritten };
}

/** @type {import('./compression.mjs').InflateFn} */
export function nodeInflate(stored, maxOutputLength) {
  try {
    return unpack(/** @type {any} */ (zlib.inflateSync(stored, bounded(maxOutputLength))));
  } catch (err) {
    return rethrow(err);
  }
}

/**
 * Brotli (§6, method 2) with zlib.brotliDecompressSync: a truncated stream is Z_BUF_ERROR ("unexpected
 * end of file"), an invalid one an ERR__ERROR_FORMAT_* code; Node's decoder stops at the stream's
 * end without complaint about bytes after it, which `consumed` tells.
 * @type {import('./compression.mjs').BrotliFn}
 */
export function nodeBrotli(stored, maxOutputLength) {
  try {
    return unpack(/** @type {any} */ (zlib.brotliDecompressSync(stored, bounded(maxOutputLength))));
  } catch (err) {
    return rethrow(err);
  }
}

/**
 * readPln of index.mjs, decompressing with node:zlib unless options.inflate or options.brotli say
 * otherwise.
 * @param {ArrayBuffer | Uint8Array} bytes
 * @param {import('./index.mjs').ReadOptions} [options]
 */
export function readPln(bytes, options = {}) {
  return readPlnCore(bytes, { inflate: nodeInflate, brotli: nodeBrotli, ...options });
}
