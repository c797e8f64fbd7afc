// node js/cli.mjs: the runner's contract (JSON and exit 0, or {"error"} and exit 1) and --obj,
// which writes the decoded scene atomically and nothing for an invalid file.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { spawnSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';

const HERE = path.dirname(fileURLToPath(import.meta.url));
const CLI = path.join(HERE, '../cli.mjs');
const SUITE = path.join(HERE, '../../conformance');

const run = (/** @type {string[]} */ ...args) => spawnSync(process.execPath, [CLI, ...args], { encoding: 'utf8' });

test('a valid file: JSON on stdout, exit 0; --obj writes its triangles in world coordinates', () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'pln-js-cli-'));
  const out = path.join(dir, 'scene.obj');
  const r = run(path.join(SUITE, 'valid/scene_hierarchy.pln'), '--obj', out);
  assert.equal(r.status, 0);
  const json = JSON.parse(r.stdout);
  const triangles = json.geometry.groups.reduce((/** @type {number} */ s, /** @type {any} */ g) => s + g.triangles, 0);
  const obj = fs.readFileSync(out, 'utf8');
  assert.equal(obj.split('\n').filter((l) => l.startsWith('f ')).length, triangles);
  assert.deepEqual(fs.readdirSync(dir), ['scene.obj']);
  fs.rmSync(dir, { recursive: true });
});

test('an invalid file: {"error": CODE} on stdout, exit 1, and no OBJ', () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'pln-js-cli-'));
  const r = run(path.join(SUITE, 'invalid/xcrc_plns.pln'), '--obj', path.join(dir, 'x.obj'));
  assert.equal(r.status, 1);
  assert.deepEqual(JSON.parse(r.stdout), { error: 'CRC_MISMATCH' });
  assert.deepEqual(fs.readdirSync(dir), []);
  fs.rmSync(dir, { recursive: true });
});
