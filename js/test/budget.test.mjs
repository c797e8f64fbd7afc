// The decode budget of spec §12.4 and the other bounds of issue 49 (items 1, 5, 6, 7, 10), on small
// files made here: each ends in LIMIT_EXCEEDED (or the reader's own code) before its memory is spent,
// and decodes once the caller raises the limit.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';
import { readPln } from '../src/node.mjs';
import { DEFAULT_LIMITS } from '../src/compression.mjs';
import { budgetFile, common, f64, outcome, varint, walkFile, zeroPlanes } from './files.mjs';

const CLI = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../cli.mjs');

/** The unit cube's six planes (ν, φ, h): -z, +z, -y, +y, -x, +x. */
const CUBE = [[Math.PI, 0, 0], [0, 0, 1], [Math.PI / 2, 1.5 * Math.PI, 0], [Math.PI / 2, Math.PI / 2, 1],
  [Math.PI / 2, Math.PI, 0], [Math.PI / 2, 0, 1]];
const cubeBlock = () => {
  const raw = CUBE.flat().flatMap(f64);
  return Uint8Array.from([0, 6, 0, ...[raw.length & 0x7f | 0x80, raw.length >> 7], ...raw]);
};

/** The convex cube (group 0) and `copies` copies of it. */
const cubeCopies = (/** @type {number} */ copies) => budgetFile({
  coding: 1,
  blocks: [cubeBlock()],
  groups: [{ kind: 0, body: Uint8Array.from(common([0, 1, 2, 3, 4, 5])) },
    ...Array.from({ length: copies }, () => ({ kind: 11, body: Uint8Array.from([...common([0, 1, 2, 3, 4, 5]), 0]) }))],
});

test('§12.4: the defaults, 2^22 triangles, vertices and planes', () => {
  assert.equal(DEFAULT_LIMITS.triangles, 2 ** 22);
  assert.equal(DEFAULT_LIMITS.vertices, 2 ** 22);
  assert.equal(DEFAULT_LIMITS.planes, 2 ** 22);
});

test('item 7: a walk declaring 5,000,000 triangles in 25 KB is LIMIT_EXCEEDED as its counts are read', () => {
  const bytes = walkFile(5_000_000);
  assert.ok(bytes.length < 30_000, `${bytes.length} bytes`);
  assert.equal(outcome(bytes), 'LIMIT_EXCEEDED');
  assert.equal(outcome(bytes, readPln, { decode: false }), 'LIMIT_EXCEEDED'); // the container alone: declared
});

test('item 7: a raised limit decodes the walk; one below it refuses it, by vertices or by triangles', () => {
  const bytes = walkFile(1000);
  assert.equal(outcome(bytes, readPln, { limits: { triangles: 999 } }), 'LIMIT_EXCEEDED');
  assert.equal(outcome(bytes, readPln, { limits: { vertices: 1001 } }), 'LIMIT_EXCEEDED');
  const mesh = readPln(bytes, { limits: { triangles: 1000, vertices: 1002 } }).mesh();
  assert.equal(mesh.indices.length / 3, 1000);
});

test('item 1: copies count their source again: a walk and its copies past the limit', () => {
  const bytes = walkFile(100, 1, 20); // 2,100 triangles, 2,142 vertices in all
  assert.equal(outcome(bytes, readPln, { limits: { triangles: 2099 } }), 'LIMIT_EXCEEDED');
  assert.equal(outcome(bytes, readPln, { decode: false, limits: { triangles: 2099 } }), 'LIMIT_EXCEEDED');
  assert.equal(readPln(bytes, { limits: { triangles: 2100 } }).mesh().indices.length / 3, 2100);
});

test('item 1: a copies bomb (one 3,394-triangle walk, 5,000 copies) is refused at the copy whose corners pass 2^22', () => {
  const bytes = walkFile(3394, 1, 5000);
  assert.throws(() => readPln(bytes), (err) => err.code === 'LIMIT_EXCEEDED' && /group 1235\b/.test(err.message));
});

test('item 1: copies of a convex group (output known once decoded) are charged after decoding', () => {
  const bytes = cubeCopies(2); // 12 triangles, 8 corners each
  assert.equal(outcome(bytes, readPln, { limits: { triangles: 35 } }), 'LIMIT_EXCEEDED');
  assert.equal(outcome(bytes, readPln, { limits: { vertices: 23 } }), 'LIMIT_EXCEEDED');
  assert.equal(outcome(bytes, readPln, { decode: false, limits: { triangles: 35 } }), 'ok');
  assert.equal(readPln(bytes, { limits: { triangles: 36, vertices: 24 } }).mesh().indices.length / 3, 36);
});

test('item 5: 5,000,000 zero planes in a deflated PLNS are LIMIT_EXCEEDED before they are inflated', () => {
  const bytes = budgetFile({ blocks: [zeroPlanes(0, 5_000_000)], groups: [] });
  assert.ok(bytes.length < 100_000);
  assert.equal(outcome(bytes), 'LIMIT_EXCEEDED');
  const small = budgetFile({ blocks: [zeroPlanes(0, 1000)], groups: [] });
  assert.equal(outcome(small, readPln, { limits: { planes: 999 } }), 'LIMIT_EXCEEDED');
  assert.equal(readPln(small, { limits: { planes: 1000 } }).planes.length, 3000);
});

test('item 10: an h range whose width overflows binary64 is BAD_HEADER_VALUE', () => {
  const bad = budgetFile({ coding: 2, bits: [8, 8, 8], hRange: [-1.7e308, 1.7e308], groups: [] });
  assert.equal(outcome(bad), 'BAD_HEADER_VALUE');
  const wide = budgetFile({ coding: 2, bits: [8, 8, 8], hRange: [-8e307, 8e307], groups: [] });
  assert.equal(outcome(wide), 'ok');
});

test('js/cli.mjs --max-triangles raises the limit; a bad number is a usage error', () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'pln-budget-'));
  try {
    const file = path.join(dir, 'walk.pln');
    fs.writeFileSync(file, walkFile(100, 1, 20));
    const run = (/** @type {string[]} */ args) => {
      try {
        return { code: 0, out: execFileSync(process.execPath, [CLI, file, ...args], { encoding: 'utf8', stdio: 'pipe' }) };
      } catch (err) {
        return { code: /** @type {any} */ (err).status, out: /** @type {any} */ (err).stdout };
      }
    };
    assert.deepEqual(run(['--max-triangles', '2099']), { code: 1, out: '{"error":"LIMIT_EXCEEDED"}\n' });
    assert.equal(run(['--max-triangles', '2100']).code, 0);
    assert.equal(run(['--max-triangles', 'many']).code, 2);
  } finally {
    fs.rmSync(dir, { recursive: true, force: true });
  }
});

/**
 * A kind 3 patch: the prism of `n` sides 2 wide (sides, then +z, then -z), its +z face reference
 * given `k` times (§9.8): n · 2 + (n − 2) · (k + 1) triangles from n + k + 1 references.
 */
const prismPatch = (/** @type {number} */ n, /** @type {number} */ k) => {
  const planes = [...Array.from({ length: n }, (_, j) => [Math.PI / 2, (2 * Math.PI * j) / n, 1]), [0, 0, 1], [Math.PI, 0, 1]];
  const raw = planes.flat().flatMap(f64);
  const block = Uint8Array.from([0, ...varint(planes.length), 0, ...varint(raw.length), ...raw]);
  const refs = [...Array.from({ length: n }, (_, j) => j), ...new Array(k).fill(n), n + 1];
  return budgetFile({ coding: 1, blocks: [block], groups: [{ kind: 3, body: Uint8Array.from(common(refs)), method: 1 }] });
};

test('§9.8, §12.4: a repeated face reference yields its face each time, counted before it is made', () => {
  const bytes = prismPatch(40, 30);
  assert.equal(readPln(bytes).mesh().indices.length / 3, 80 + 38 * 31);
  assert.equal(readPln(prismPatch(8, 20)).mesh().indices.length / 3, 16 + 6 * 21); // past 14 references too
  assert.throws(() => readPln(bytes, { limits: { triangles: 80 + 38 * 31 - 1 } }),
    (err) => err.code === 'LIMIT_EXCEEDED' && /repeated face references make 1258 triangles/.test(err.message));
});
