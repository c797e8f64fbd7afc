// The real corpus (tests/corpus, or PLN_CORPUS) encoded by planefmt's default encoder as version 5
// and, where the encoder writes it, version 6 (`pln convert --major 5`, `--major 6`), and decoded
// here and by planefmt (planefmt_decode.py): the two decodings must agree within 1e-9 of the
// bounding-box diagonal, vertex set against vertex set both ways, triangle count, and area.
// PLANEFMT_ROOT names the planefmt checkout whose .venv encodes and decodes (bench/corpus.mjs).
// One file per category by default (under a minute on two busy cores); PLN_JS_CORPUS=all runs
// every file. Encoded files are cached in the temporary directory, keyed by source and encoder.
// Two more files encoded with the paper's scheme (trees and patches) check the union of trees
// by area, volume and extent: planefmt splits edges at T-junctions and this reader does not, so
// their triangles differ.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { readPln } from '../src/node.mjs';
import { execFileSync } from 'node:child_process';
import { conformanceJson } from '../src/report.mjs';
import { available, allFiles, encoded, encoderMajors, PYTHON, ROOT } from '../bench/corpus.mjs';
import { planefmtDecoding as reference } from './files.mjs';

const SUBSET = [
  'cad/angle_block.STL', 'convex/test_sphere.stl', 'convex/tet.ply', 'gltf_scene/simple_pole.glb',
  'gltf_scene/boolean.glb', 'nonconvex_watertight/round.stl', 'open/soup.stl', 'smooth_dense/npm_bunny.ply',
  'usd/bolt.usda',
];
const REL = 1e-9;

/** The largest distance from a point of a to the nearest point of b. */
function oneSided(/** @type {Float64Array} */ a, /** @type {Float64Array} */ b, /** @type {number} */ cell) {
  /** @type {Map<string, number[]>} */
  const grid = new Map();
  const key = (/** @type {number} */ x, /** @type {number} */ y, /** @type {number} */ z) => `${x},${y},${z}`;
  for (let i = 0; i < b.length; i += 3) {
    const k = key(Math.floor(b[i] / cell), Math.floor(b[i + 1] / cell), Math.floor(b[i + 2] / cell));
    if (!grid.has(k)) grid.set(k, []);
    /** @type {number[]} */ (grid.get(k)).push(i);
  }
  let worst = 0;
  for (let i = 0; i < a.length; i += 3) {
    const [cx, cy, cz] = [Math.floor(a[i] / cell), Math.floor(a[i + 1] / cell), Math.floor(a[i + 2] / cell)];
    let best = Infinity;
    for (let dx = -1; dx <= 1; dx++) for (let dy = -1; dy <= 1; dy++) for (let dz = -1; dz <= 1; dz++) {
      for (const j of grid.get(key(cx + dx, cy + dy, cz + dz)) ?? []) {
        best = Math.min(best, Math.hypot(a[i] - b[j], a[i + 1] - b[j + 1], a[i + 2] - b[j + 2]));
      }
    }
    worst = Math.max(worst, best); // Infinity: nothing within a cell
  }
  return worst;
}

/** @param {Float64Array} p @param {Uint32Array} ix */
function area(p, ix) {
  let s = 0;
  for (let t = 0; t < ix.length; t += 3) {
    const [a, b, c] = [3 * ix[t], 3 * ix[t + 1], 3 * ix[t + 2]];
    const u = [p[b] - p[a], p[b + 1] - p[a + 1], p[b + 2] - p[a + 2]];
    const v = [p[c] - p[a], p[c + 1] - p[a + 1], p[c + 2] - p[a + 2]];
    s += Math.hypot(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]) / 2;
  }
  return s;
}

/** @param {Float64Array} p */
function diagonal(p) {
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < p.length; i += 3) {
    for (let r = 0; r < 3; r++) {
      lo[r] = Math.min(lo[r], p[i + r]);
      hi[r] = Math.max(hi[r], p[i + r]);
    }
  }
  return Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
}

/**
 * Compares this reader's decoding of a .pln file with planefmt's.
 * @param {string} file
 */
function compare(file) {
  const mine = readPln(fs.readFileSync(file)).mesh();
  const ref = reference(file);
  const D = diagonal(ref.positions);
  const tol = REL * D;
  return {
    D,
    distance: Math.max(oneSided(mine.positions64, ref.positions, tol * 4), oneSided(ref.positions, mine.positions64, tol * 4)),
    triangles: [mine.indices.length / 3, ref.indices.length / 3],
    area: [area(mine.positions64, mine.indices), area(ref.positions, ref.indices)],
    tol,
  };
}

const files = process.env.PLN_JS_CORPUS === 'all' ? (available ? allFiles() : []) : SUBSET;

for (const major of [5, 6]) {
  const skip = !available ? 'no .venv or corpus' : !encoderMajors().includes(major) && `the encoder writes no version ${major}`;
  for (const rel of files) {
    test(`corpus ${rel} as version ${major}: this decoder and planefmt's agree within ${REL} of the diagonal`, { skip }, (t) => {
      const file = encoded(rel, ['--major', String(major)]);
      assert.equal(readPln(fs.readFileSync(file), { decode: false }).version[0], major);
      const r = compare(file);
      t.diagnostic(`${fs.statSync(file).size} bytes, vertex sets ${(r.distance / r.D).toExponential(1)} of the diagonal apart, ${r.triangles[0]} triangles`);
      assert.ok(r.distance <= r.tol, `vertex sets ${r.distance / r.D} of the diagonal apart`);
      assert.equal(r.triangles[0], r.triangles[1], 'triangles');
      assert.ok(Math.abs(r.area[0] - r.area[1]) <= REL * r.area[1], `areas ${r.area}`);
    });
  }
}

const PAPER = ['nonconvex_watertight/round.stl', 'open/not_convex.obj'];

/** Area, volume and bounding box of a mesh. @param {Float64Array} p @param {Uint32Array} ix */
function measures(p, ix) {
  let volume = 0;
  for (let t = 0; t < ix.length; t += 3) {
    const [a, b, c] = [3 * ix[t], 3 * ix[t + 1], 3 * ix[t + 2]];
    volume += (p[a] * (p[b + 1] * p[c + 2] - p[b + 2] * p[c + 1]) - p[a + 1] * (p[b] * p[c + 2] - p[b + 2] * p[c])
      + p[a + 2] * (p[b] * p[c + 1] - p[b + 1] * p[c])) / 6;
  }
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < p.length; i += 3) {
    for (let r = 0; r < 3; r++) {
      lo[r] = Math.min(lo[r], p[i + r]);
      hi[r] = Math.max(hi[r], p[i + r]);
    }
  }
  return { area: area(p, ix), volume, box: [...lo, ...hi] };
}

for (const rel of PAPER) {
  test(`corpus ${rel} by the paper's scheme: the same area, volume and extent within ${REL}`, { skip: !available && 'no .venv or corpus' }, () => {
    const file = encoded(rel, ['--scheme', 'paper']);
    const mine = readPln(fs.readFileSync(file)).mesh();
    const ref = reference(file);
    const a = measures(mine.positions64, mine.indices);
    const b = measures(ref.positions, ref.indices);
    const D = diagonal(ref.positions);
    assert.ok(Math.abs(a.area - b.area) <= REL * b.area, `areas ${a.area} ${b.area}`);
    assert.ok(Math.abs(a.volume - b.volume) <= REL * Math.abs(b.volume), `volumes ${a.volume} ${b.volume}`);
    a.box.forEach((v, i) => assert.ok(Math.abs(v - b.box[i]) <= REL * D, `box ${a.box} ${b.box}`));
  });
}

/** planefmt's conformance report of a file (conformance/adapter.py of the planefmt checkout). @param {string} file */
function planefmtReport(file) {
  const out = execFileSync(PYTHON, ['-m', 'conformance.adapter', file], { cwd: ROOT, maxBuffer: 1 << 30 });
  return JSON.parse(out.toString());
}

// The container as both readers report it (conformance/README.md's contract): the header, the plane
// table (quantized values within 1e-12 of their range, §7.3's formula in another order), objects,
// groups with their kind data, colours, metadata and findings, on version 6 files made by planefmt.
{
  const skip = !available ? 'no .venv or corpus' : !encoderMajors().includes(6) && 'the encoder writes no version 6';
  for (const rel of SUBSET) {
    test(`corpus ${rel} as version 6: the container reported as planefmt reports it`, { skip }, () => {
      const file = encoded(rel, ['--major', '6']);
      const want = planefmtReport(file);
      const got = JSON.parse(JSON.stringify(conformanceJson(readPln(fs.readFileSync(file)))));
      assert.deepEqual(got.header, want.header);
      const [h0, h1] = want.header.h_range;
      const tol = want.header.coding >= 2 ? [1e-12, 1e-12, 1e-12 * Math.max(1, Math.abs(h0), Math.abs(h1))] : [0, 0, 0];
      assert.equal(got.planes.length, want.planes.length);
      want.planes.forEach((/** @type {number[]} */ w, /** @type {number} */ i) => {
        assert.ok(w.every((v, k) => Math.abs(got.planes[i][k] - v) <= tol[k]), `plane ${i}`);
      });
      for (const key of ['objects', 'groups', 'colours', 'metadata']) assert.deepEqual(got[key], want[key], key);
      assert.deepEqual(got.findings.sort(), want.findings.sort());
    });
  }
}
