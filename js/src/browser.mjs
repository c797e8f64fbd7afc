/**
 * The browser entry: readPln with fflate's inflater (npm `fflate`, resolved by an import map).
 * fflate neither checks the Adler-32 value nor says where the stream ended, so a corrupt check
 * value or bytes after the stream pass here where node.mjs reports them (spec §6); valid files
 * read the same.
 */
import { unzlibSync } from 'fflate';
import { readPln as readPlnCore, PlnError } from './index.mjs';

export { PlnError };

/** @type {import('./compression.mjs').InflateFn} */
export function fflateInflate(stored, maxOutputLength) {
  try {
    return unzlibSync(stored, { out: new Uint8Array(maxOutputLength) });
  } catch (err) {
    const e = /** @type {any} */ (err);
    if (e.code === 0) e.truncated = true; // fflate's "unexpected EOF"
    throw e;
  }
}

/**
 * readPln of index.mjs, inflating with fflate unless options.inflate says otherwise.
 * @param {ArrayBuffer | Uint8Array} bytes
 * @param {import('./index.mjs').ReadOptions} [options]
 */
export function readPln(bytes, options = {}) {
  return readPlnCore(bytes, { inflate: fflateInflate, ...options });
}
