// Decoding speed in Node: this reader on planefmt's default encoding of each corpus mesh of at
// least 1,000 triangles, beside Draco's JavaScript (WebAssembly) decoder, draco3d, on the same
// triangles encoded by draco3d at 14 quantization bits. Both timings take a file's bytes to
// typed arrays of positions and triangle indices (for .pln also per-triangle colours where the
// file has them). Prints one line per mesh and the geometric mean of the speed ratios.
//
//   node js/bench/decode.mjs [--min-ms 300] [--markdown]
import fs from 'node:fs';
import path from 'node:path';
import draco3d from 'draco3d';
import { readPln } from '../src/node.mjs';
import { available, allFiles, encoded } from './corpus.mjs';

const args = process.argv.slice(2);
const MIN_MS = Number(args[args.indexOf('--min-ms') + 1]) || 300;
const MARKDOWN = args.includes('--markdown');
const MIN_TRIANGLES = 1000;

/** Median milliseconds of fn over at least MIN_MS and 5 runs, after 2 warm-up runs. */
function time(/** @type {() => unknown} */ fn) {
  fn();
  fn();
  const runs = [];
  const start = performance.now();
  while (runs.length < 5 || performance.now() - start < MIN_MS) {
    const t = performance.now();
    fn();
    runs.push(performance.now() - t);
  }
  runs.sort((a, b) => a - b);
  return runs[runs.length >> 1];
}

/** Draco bytes of a mesh: edgebreaker, positions at 14 bits, draco_encoder's default speed. */
function dracoEncode(/** @type {any} */ E, /** @type {Float32Array} */ positions, /** @type {Uint32Array} */ indices) {
  const encoder = new E.Encoder();
  const builder = new E.MeshBuilder();
  const mesh = new E.Mesh();
  builder.AddFacesToMesh(mesh, indices.length / 3, indices);
  builder.AddFloatAttributeToMesh(mesh, E.POSITION, positions.length / 3, 3, positions);
  encoder.SetAttributeQuantization(E.POSITION, 14);
  encoder.SetSpeedOptions(3, 3);
  encoder.SetEncodingMethod(E.MESH_EDGEBREAKER_ENCODING);
  const out = new E.DracoInt8Array();
  const length = encoder.EncodeMeshToDracoBuffer(mesh, out);
  const bytes = new Int8Array(length);
  for (let i = 0; i < length; i++) bytes[i] = out.GetValue(i);
  for (const o of [out, mesh, builder, encoder]) E.destroy(o);
  return bytes;
}

/** Positions and triangles out of Draco bytes, as a viewer takes them. */
function dracoDecode(/** @type {any} */ D, /** @type {Int8Array} */ bytes) {
  const buffer = new D.DecoderBuffer();
  buffer.Init(bytes, bytes.length);
  const decoder = new D.Decoder();
  const mesh = new D.Mesh();
  const status = decoder.DecodeBufferToMesh(buffer, mesh);
  if (!status.ok()) throw new Error(status.error_msg());
  const nt = mesh.num_faces();
  const np = mesh.num_points();
  const ptr = D._malloc(12 * Math.max(nt, np));
  decoder.GetTrianglesUInt32Array(mesh, 12 * nt, ptr);
  const indices = new Uint32Array(D.HEAPU32.buffer, ptr, 3 * nt).slice();
  const attribute = decoder.GetAttribute(mesh, decoder.GetAttributeId(mesh, D.POSITION));
  decoder.GetAttributeDataArrayForAllPoints(mesh, attribute, D.DT_FLOAT32, 12 * np, ptr);
  const positions = new Float32Array(D.HEAPF32.buffer, ptr, 3 * np).slice();
  D._free(ptr);
  for (const o of [mesh, decoder, buffer]) D.destroy(o);
  return { positions, indices };
}

async function main() {
  if (!available) throw new Error('needs the repository .venv (make setup) and the corpus');
  const [E, D] = await Promise.all([draco3d.createEncoderModule({}), draco3d.createDecoderModule({})]);
  const rows = [];
  for (const rel of allFiles()) {
    const bytes = new Uint8Array(fs.readFileSync(encoded(rel)));
    const mesh = readPln(bytes).mesh();
    const triangles = mesh.indices.length / 3;
    if (triangles < MIN_TRIANGLES) continue;
    const draco = dracoEncode(E, mesh.positions, mesh.indices);
    if (dracoDecode(D, draco).indices.length !== mesh.indices.length) throw new Error(`${rel}: Draco lost triangles`);
    const pln = time(() => readPln(bytes));
    const dr = time(() => dracoDecode(D, draco));
    rows.push({ name: path.basename(rel), triangles, plnBytes: bytes.length, dracoBytes: draco.length, pln, draco: dr });
  }
  const ratios = rows.map((r) => r.draco / r.pln);
  const geomean = Math.exp(ratios.reduce((s, r) => s + Math.log(r), 0) / ratios.length);
  const f = (/** @type {number} */ x, /** @type {number} */ d) => x.toFixed(d);
  if (MARKDOWN) {
    console.log('| mesh | triangles | .pln bytes | Draco bytes | .pln ms | Draco ms | .pln Mtri/s | Draco Mtri/s | speed .pln / Draco |');
    console.log('|---|---:|---:|---:|---:|---:|---:|---:|---:|');
  }
  for (const r of rows) {
    const cells = [r.name, r.triangles, r.plnBytes, r.dracoBytes, f(r.pln, 3), f(r.draco, 3),
      f(r.triangles / r.pln / 1e3, 2), f(r.triangles / r.draco / 1e3, 2), f(r.draco / r.pln, 2)];
    console.log(MARKDOWN ? `| ${cells.join(' | ')} |` : cells.join('\t'));
  }
  console.log(`${MARKDOWN ? '\n' : ''}geometric mean of speed .pln / Draco over ${rows.length} meshes: ${f(geomean, 2)}`);
}

await main();
