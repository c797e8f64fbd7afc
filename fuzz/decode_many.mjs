// node fuzz/decode_many.mjs INPUTS SLOW_S: decodes every input of INPUTS (each a u32 length, then
// its bytes; fuzz/mutations.py writes them) with readPln(..., {decode: true}) and prints one JSON
// object: counts of results, PlnErrors, foreign exceptions (their places), inputs over SLOW_S.
import fs from 'node:fs';
import { readPln, PlnError } from '../js/src/node.mjs';

const [file, slowArg] = process.argv.slice(2);
const slow = Number(slowArg ?? 2) * 1000;
const blob = new Uint8Array(fs.readFileSync(file));
const view = new DataView(blob.buffer, blob.byteOffset, blob.byteLength);
const report = { inputs: 0, results: 0, errors: 0, foreign: 0, slow: 0, slowest_s: 0,
  foreign_by_place: {}, foreign_at: [], slow_at: [] };
for (let pos = 0; pos < blob.length; report.inputs++) {
  const n = view.getUint32(pos, true);
  const data = blob.slice(pos + 4, pos + 4 + n);
  pos += 4 + n;
  const t0 = performance.now();
  try {
    readPln(data, { decode: true });
    report.results++;
  } catch (err) {
    if (err instanceof PlnError) report.errors++;
    else {
      report.foreign++;
      report.foreign_at.push(report.inputs);
      const where = `${err?.name}: ${String(err?.stack ?? err).split('\n')[1]?.trim()}`;
      report.foreign_by_place[where] = (report.foreign_by_place[where] ?? 0) + 1;
    }
  }
  const took = performance.now() - t0;
  report.slowest_s = Math.max(report.slowest_s, Math.round(took) / 1000);
  if (took > slow) {
    report.slow++;
    report.slow_at.push(report.inputs);
  }
}
process.stdout.write(`${JSON.stringify(report)}\n`);
