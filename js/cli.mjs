#!/usr/bin/env node
/**
 * node js/cli.mjs FILE [--obj OUT.obj] [--max-triangles N] [--max-vertices N] [--max-planes N]
 *
 * The conformance runner's contract (conformance/README.md): one JSON object on stdout and exit 0
 * for a valid file, {"error": "CODE"} and exit 1 for an invalid one. With --obj, also the decoded
 * scene in world coordinates as a Wavefront OBJ, written to a temporary file and renamed. The --max
 * options raise (or lower) the reader's limits of §12.4: the triangles and vertices of the whole
 * decode, the planes of the table (2^22 each by default).
 */
import fs from 'node:fs';
import path from 'node:path';
import { readPln, PlnError } from './src/node.mjs';
import { conformanceJson } from './src/report.mjs';
import { toObj } from './src/obj.mjs';

const USAGE = 'usage: node js/cli.mjs FILE [--obj OUT.obj] [--max-triangles N] [--max-vertices N] [--max-planes N]\n';

/** The option of each --max flag in the reader's limits (§12.4). */
const LIMIT_FLAGS = { '--max-triangles': 'triangles', '--max-vertices': 'vertices', '--max-planes': 'planes' };

/** @param {string[]} argv */
function main(argv) {
  const args = argv.slice(2);
  const objAt = args.indexOf('--obj');
  let objPath = null;
  if (objAt >= 0) {
    objPath = args[objAt + 1];
    args.splice(objAt, 2);
  }
  /** @type {Record<string, number>} */
  const limits = {};
  for (const [flag, key] of Object.entries(LIMIT_FLAGS)) {
    const at = args.indexOf(flag);
    if (at < 0) continue;
    const n = Number(args[at + 1]);
    if (!Number.isSafeInteger(n) || n < 0) {
      process.stderr.write(`${flag} takes a whole number, not ${args[at + 1]}\n${USAGE}`);
      return 2;
    }
    limits[key] = n;
    args.splice(at, 2);
  }
  if (args.length !== 1 || (objAt >= 0 && !objPath)) {
    process.stderr.write(USAGE);
    return 2;
  }
  let file;
  try {
    file = readPln(new Uint8Array(fs.readFileSync(args[0])), { decode: true, limits });
  } catch (err) {
    if (!(err instanceof PlnError)) throw err;
    process.stdout.write(`${JSON.stringify({ error: err.code })}\n`);
    process.stderr.write(`${err.message}${err.chunk ? ` (${err.chunk} at ${err.offset})` : ''}\n`);
    return 1;
  }
  if (objPath) {
    const tmp = path.join(path.dirname(objPath), `.${path.basename(objPath)}.${process.pid}.tmp`);
    try {
      fs.writeFileSync(tmp, toObj(file));
      fs.renameSync(tmp, objPath);
    } catch (err) {
      fs.rmSync(tmp, { force: true });
      throw err;
    }
  }
  process.stdout.write(`${JSON.stringify(conformanceJson(file))}\n`);
  return 0;
}

process.exitCode = main(process.argv);
