// Every case of conformance/manifest.tsv in process, compared as conformance/runner.py compares
// at --level geometry.
// And the browser entry (fflate) reads every valid file as the Node entry does.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readPln, PlnError } from '../src/node.mjs';
import { readPln as readPlnBrowser } from '../src/browser.mjs';
import { conformanceJson } from '../src/report.mjs';
import { manifest, suiteFile, caseJson } from './files.mjs';

const cases = manifest().map(([file, expected, level]) => ({ file, expected, level }));

/** @param {string} file */
function outcome(file) {
  try {
    return JSON.parse(JSON.stringify(conformanceJson(readPln(suiteFile(file), { decode: true }))));
  } catch (err) {
    if (err instanceof PlnError) return { error: err.code };
    throw err;
  }
}

/** @param {any} a @param {any} b @param {number} tol @returns {boolean} */
function close(a, b, tol) {
  if (Array.isArray(b)) return Array.isArray(a) && a.length === b.length && a.every((x, i) => close(x, b[i], tol));
  return typeof a === 'number' && Math.abs(a - b) <= tol;
}

/** @param {number[][]} box */
const diagonal = (box) => Math.hypot(box[1][0] - box[0][0], box[1][1] - box[0][1], box[1][2] - box[0][2]);

/** @param {any} want @param {any} got */
function compareValid(want, got) {
  for (const key of Object.keys(want.header)) assert.deepEqual(got.header[key], want.header[key], `header.${key}`);
  const tol = want.header.coding === 2
    ? [1e-12, 1e-12, 1e-12 * Math.max(1, ...want.header.h_range.map(Math.abs))] : [0, 0, 0];
  assert.equal(got.planes.length, want.planes.length, 'plane count');
  want.planes.forEach((/** @type {number[]} */ w, /** @type {number} */ i) => {
    assert.ok(w.every((v, k) => Math.abs(got.planes[i][k] - v) <= tol[k]), `plane ${i}`);
  });
  // JSON.stringify writes −0 as 0 and the golden files keep −0.0 (4.0 transforms code it as an
  // f32); the runner's Python == takes them as equal, so both sides as JSON writes them
  const asJson = (/** @type {any} */ v) => JSON.parse(JSON.stringify(v));
  for (const key of ['objects', 'groups', 'colours']) assert.deepEqual(got[key], asJson(want[key]), key);
  if ('metadata' in want) assert.deepEqual(got.metadata, want.metadata);
  const allowed = new Set([...want.findings, ...want.findings_optional]);
  for (const f of want.findings) assert.ok(got.findings.includes(f), `finding ${f}`);
  for (const f of got.findings) assert.ok(allowed.has(f), `finding ${f}`);
  const w = want.geometry;
  const g = got.geometry;
  assert.ok(g, 'geometry');
  if (w.world_bbox) assert.ok(close(g.world_bbox, w.world_bbox, w.tolerance * diagonal(w.world_bbox)), 'world_bbox');
  assert.equal(g.groups.length, w.groups.length);
  w.groups.forEach((/** @type {any} */ ws, /** @type {number} */ k) => {
    const gs = g.groups[k];
    if (ws === null) return assert.equal(gs, null);
    const d = diagonal(ws.bbox);
    for (const [key, scale] of [['bbox', d], ['area', d * d], ['area_vector', d * d], ['volume', d ** 3]]) {
      if (ws[key] !== null) assert.ok(close(gs[key], ws[key], w.tolerance * /** @type {number} */ (scale)), `group ${k} ${key}: ${gs[key]} vs ${ws[key]}`);
    }
    for (const key of ['vertices', 'triangles']) if (ws[key] !== null) assert.equal(gs[key], ws[key], `group ${k} ${key}`);
  });
}

for (const c of cases) {
  test(c.file, () => {
    const want = caseJson(c.file);
    const got = outcome(c.file);
    if ('error' in want) {
      assert.ok([want.error, ...want.also].includes(got.error), `got ${got.error ?? 'a valid file'}, expected ${want.error}`);
    } else {
      assert.equal(got.error, undefined, `rejected: ${got.error}`);
      compareValid(want, got);
    }
  });
}

test('the browser entry (fflate) reads the valid files as the Node entry does', () => {
  for (const c of cases.filter((k) => k.expected === 'ok')) {
    const bytes = suiteFile(c.file);
    const a = conformanceJson(readPln(bytes));
    const b = conformanceJson(readPlnBrowser(bytes));
    assert.deepEqual(b, a, c.file);
  }
});
