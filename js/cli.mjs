#!/usr/bin/env node
/**
 * node js/cli.mjs FILE [--obj OUT.obj]
 *
 * The conformance runner's contract (conformance/README.md): one JSON object on stdout and exit 0
 * for a valid file, {"error": "CODE"} and exit 1 for an invalid one. With --obj, also the decoded
 * scene in world coordinates as a Wavefront OBJ, written to a temporary file and renamed.
 */
import fs from 'node:fs';
import path from 'node:path';
import { readPln, PlnError } from './src/node.mjs';
import { conformanceJson } from './src/report.mjs';
import { toObj } from './src/obj.mjs';

/** @param {string[]} argv */
function main(argv) {
  const args = argv.slice(2);
  const objAt = args.indexOf('--obj');
  let objPath = null;
  if (objAt >= 0) {
    objPath = args[objAt + 1];
    args.splice(objAt, 2);
  }
  if (args.length !== 1 || (objAt >= 0 && !objPath)) {
    process.stderr.write('usage: node js/cli.mjs FILE [--obj OUT.obj]\n');
    return 2;
  }
  let file;
  try {
    file = readPln(new Uint8Array(fs.readFileSync(args[0])), { decode: true });
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
