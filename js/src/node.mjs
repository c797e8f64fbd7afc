/** The Node entry: readPln with Node's zlib as its default inflater. */
import { readPln as readPlnCore, PlnError } from './index.mjs';
import { nodeInflate } from './node-inflate.mjs';

export { PlnError };

/**
 * readPln of index.mjs, inflating with node:zlib unless options.inflate says otherwise.
 * @param {ArrayBuffer | Uint8Array} bytes
 * @param {import('./index.mjs').ReadOptions} [options]
 */
export function readPln(bytes, options = {}) {
  return readPlnCore(bytes, { inflate: nodeInflate, ...options });
}
