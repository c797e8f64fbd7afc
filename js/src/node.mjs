/** The Node entry: readPln with Node's zlib as its inflater (the one module here importing Node). */
import zlib from 'node:zlib';
import { readPln as readPlnCore, PlnError } from './index.mjs';

export { PlnError };

/** @type {import('./compression.mjs').InflateFn} */
export function nodeInflate(stored, maxOutputLength) {
  try {
    // info: the engine's bytesWritten is the input the stream took, to find bytes after its end
    const { buffer, engine } = /** @type {any} */ (zlib.inflateSync(stored, { info: true, maxOutputLength }));
    return { output: new Uint8Array(buffer.buffer, buffer.byteOffset, buffer.length), consumed: engine.bytesWritten };
  } catch (err) {
    const e = /** @type {any} */ (err);
    if (e.code === 'Z_BUF_ERROR') e.truncated = true;
    if (e.code === 'ERR_BUFFER_TOO_LARGE') e.tooLong = true;
    throw e;
  }
}

/**
 * readPln of index.mjs, inflating with node:zlib unless options.inflate says otherwise.
 * @param {ArrayBuffer | Uint8Array} bytes
 * @param {import('./index.mjs').ReadOptions} [options]
 */
export function readPln(bytes, options = {}) {
  return readPlnCore(bytes, { inflate: nodeInflate, ...options });
}
