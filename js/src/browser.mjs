/**
 * The browser entry: readPln with fflate's inflater (npm `fflate`) and brotli-dec-wasm's Brotli
 * decoder (npm `brotli-dec-wasm`, Rust's brotli-decompressor as WebAssembly, 208 KB), both resolved
 * by an import map ("fflate", "brotli-dec-wasm/web"); no build step.
 *
 * fflate neither checks the Adler-32 value nor says where the stream ended, so a corrupt check
 * value or bytes after a zlib stream pass here where node.mjs reports them (spec §6); valid files
 * read the same. The Brotli decoder says all §6 needs (an invalid stream, one the input ends inside,
 * where it ended) and is held to raw size + 1 bytes of output, as node.mjs is.
 *
 * The WebAssembly module is instantiated when this module loads (a top-level await: the
 * module's importers wait for it): in a browser fetched beside brotli-dec-wasm's script, in Node
 * read from node_modules. Should that fail, files read as before and only Brotli payloads are
 * refused (BAD_COMPRESSION, the reason in the message).
 */
import { unzlibSync } from 'fflate';
import initBrotli, { DecompressStream, BrotliStreamResultCode } from 'brotli-dec-wasm/web';
import { readPln as readPlnCore, PlnError } from './index.mjs';

export { PlnError };

/** Why the Brotli decoder is not there, or null once it is. @type {string | null} */
let brotliProblem = null;
try {
  const node = /** @type {any} */ (globalThis).process?.versions?.node;
  if (node) {
    // Node's fetch reads no file: URL; this branch never runs in a browser
    const { readFileSync } = await import('node:fs');
    const wasm = new URL('brotli_dec_wasm_bg.wasm', import.meta.resolve('brotli-dec-wasm/web'));
    await initBrotli({ module_or_path: readFileSync(wasm) });
  } else {
    await initBrotli(); // the .wasm beside the package's script, by its import.meta.url
  }
} catch (err) {
  brotliProblem = String(err);
}

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
 * One call of the streaming decoder with an output buffer of maxOutputLength bytes: it ends with
 * the stream decoded (ResultSuccess, `input_offset` where the stream ended), the input used up
 * inside the stream (NeedsMoreInput: truncated) or the buffer full with more to come
 * (NeedsMoreOutput: beyond raw size); an invalid stream throws.
 * @type {import('./compression.mjs').BrotliFn}
 */
export function wasmBrotli(stored, maxOutputLength) {
  if (brotliProblem !== null) throw new Error(`no Brotli decoder (${brotliProblem})`);
  const stream = new DecompressStream();
  try {
    const result = stream.decompress(stored, maxOutputLength);
    const { code, buf: output, input_offset: consumed } = result;
    result.free();
    if (code === BrotliStreamResultCode.NeedsMoreInput) {
      throw Object.assign(new Error('the input ends inside the Brotli stream'), { truncated: true });
    }
    if (code === BrotliStreamResultCode.NeedsMoreOutput) {
      throw Object.assign(new Error(`more than ${maxOutputLength} bytes of output`), { tooLong: true });
    }
    return { output, consumed };
  } finally {
    stream.free();
  }
}

/**
 * readPln of index.mjs, decompressing with fflate and brotli-dec-wasm unless options.inflate or
 * options.brotli say otherwise.
 * @param {ArrayBuffer | Uint8Array} bytes
 * @param {import('./index.mjs').ReadOptions} [options]
 */
export function readPln(bytes, options = {}) {
  return readPlnCore(bytes, { inflate: fflateInflate, brotli: wasmBrotli, ...options });
}
