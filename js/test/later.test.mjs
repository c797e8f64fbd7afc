// Shell walks stepping from the later gate corner (kind 13, spec §9.17, version 5.2) on files made
// here. A reference of §9.17 written in the test from its text (BigInt throughout; §9.13's walk with
// its open edges a plain list; the predictor of §9.11 with the naming triangle's max(i0, i1) in place
// of its i0, or i0 itself for kind 9's rule beside it) encodes and decodes explicit corners; the walks
// are hand-built (fans round a corner, gates either way round), a cube walked by an encoder written
// here (named and explicit corners in all 256 mixes) or taken from the golden files (a sphere and
// tori of kinds 9, 10 and 12). Predictions by hand; round trips in every mode; the rule matters (kind
// 9's rule decodes the same bytes to another shape) and the parallelogram does not change; the 5.2
// goldens against the reference; values and residuals near and past 2^52, indices outside their
// table and mode bits above 1 (BAD_GROUP_STRUCTURE), random residual sets against the reference,
// every prefix and many one-byte changes of a body; the versions (kind 13 in 5.2 and later, unknown
// in 5.0 and 5.1; kind 14 unknown in 5.2, skipped in 5.3); linear time; the 5.2 conformance cases
// through both entries; planefmt's kind 13 groups of the corpus decoded alike here and by planefmt.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { readPln as readNode } from '../src/node.mjs';
import { readPln as readBrowser } from '../src/browser.mjs';
import { conformanceJson } from '../src/report.mjs';
import { Cursor } from '../src/varint.mjs';
import { KIND_NAMES, PLNLoader } from '../three/PLNLoader.mjs';
import { available, encoded } from '../bench/corpus.mjs';
import {
  golden, manifest, suiteFile, caseJson, varint, varints, zigzag, unzigzag, f32, bigVarint, triplet, file5, groupBody, outcome, expectListed,
  shellOf, planefmtDecoding, HANG_MS,
} from './files.mjs';

const Z = 2n ** 52n;

/**
 * A version 5.2 file unless `minor` says otherwise (files.mjs's file5): the given planes, one
 * object, groups with the kind, kind data and m references (m = 0 by default).
 * @param {{kind: number, data: number[], m?: number}[]} groups @param {number} [minor]
 * @param {number[][]} [planes]
 */
const file = (groups, minor = 2, planes = []) => file5(groups, minor, planes);

// ---------------------------------------------------------------------------------------------
// The reference: §9.13's walk and §9.17's prediction, from the text

const ROOT_LISTS = ['', '0', '1', '2', '01', '02', '10', '12', '20', '21', '012', '021', '102', '120', '201', '210'];
const ATTACHED_LISTS = ['', '1', '2', '12', '21'];

/**
 * @typedef {object} Walk the fields of a walk (§9.13)
 * @property {number} V
 * @property {number} T
 * @property {number[]} symbols
 * @property {number[]} escapes
 */

/**
 * §9.13's walk: per triangle its corners (i0, i1, i2), per corner the triangle whose code 0 named it
 * (-1 for a root's), per triangle its parent's opposite corner (-1 for a root).
 * @param {Walk} w
 */
function walked({ V, T, symbols, escapes }) {
  /** @type {number[][]} */
  const tris = [];
  /** @type {number[]} */
  const namer = [];
  /** @type {number[]} */
  const opposite = [];
  /** @type {number[][]} slots [triangle, edge] */
  const stack = [];
  /** @type {number[][]} open edges [a, b], oldest first */
  const open = [];
  let x = 0;
  const name = (/** @type {number} */ j) => namer.push(j) - 1;
  /** the other end of the newest open edge with `c` at `at` (0 start, 1 end), the second newest where that is `not` */
  const newest = (/** @type {0 | 1} */ at, /** @type {number} */ c, /** @type {number} */ not) => {
    let skipped = false;
    for (let i = open.length - 1; i >= 0; i--) {
      if (open[i][at] !== c) continue;
      if (open[i][1 - at] === not && !skipped) { skipped = true; continue; }
      return open[i][1 - at];
    }
    throw new Error('left or right names nothing');
  };
  for (let j = 0; j < T; j++) {
    const s = symbols[j];
    let tri;
    let kids;
    if (stack.length === 0) {
      kids = ROOT_LISTS[s];
      tri = [0, 1, 2].map(() => {
        const c = escapes[x++];
        return c === 0 ? name(-1) : namer.length - c;
      });
      opposite.push(-1);
    } else {
      const [p, e] = /** @type {number[]} */ (stack.pop());
      const q = tris[p];
      const [i0, i1, o] = [q[(e + 1) % 3], q[e], q[(e + 2) % 3]];
      kids = ATTACHED_LISTS[s >> 2];
      const k = s & 3;
      let i2;
      if (k === 0) i2 = name(j);
      else if (k === 1) i2 = newest(1, i1, o);
      else if (k === 2) i2 = newest(0, i0, o);
      else {
        const z = escapes[x++];
        i2 = i1 + (z % 2 ? -(z + 1) / 2 : z / 2);
      }
      tri = [i0, i1, i2];
      opposite.push(o);
    }
    for (let e = 0; e < 3; e++) {
      const [a, b] = [tri[e], tri[(e + 1) % 3]];
      let i = open.length - 1;
      while (i >= 0 && !(open[i][0] === b && open[i][1] === a)) i--;
      if (i >= 0) open.splice(i, 1);
      else open.push([a, b]);
    }
    tris.push(tri);
    for (let q = kids.length - 1; q >= 0; q--) stack.push([j, Number(kids[q])]);
  }
  assert.equal(namer.length, V);
  assert.equal(stack.length, 0);
  assert.equal(x, escapes.length);
  return { tris, namer, opposite };
}

/**
 * The prediction of explicit corner k from the values g of the corners before it. §9.17: with
 * mode bit 0, §9.12's parallelogram g(i0) + g(i1) − g(o) where the naming triangle is attached and
 * all three are explicit; elsewhere the predictor: corner max(i0, i1) of the naming triangle where
 * it is attached and that corner explicit, else the previous explicit corner, else none (0).
 * `rule` 'first' is kind 9's (§9.11: i0 in place of max(i0, i1)), for comparison.
 * @param {ReturnType<typeof walked>} w @param {boolean[]} explicit @param {number} mode @param {number} k
 * @param {(k: number) => bigint[]} g @param {'later' | 'first'} [rule]
 */
function predict(w, explicit, mode, k, g, rule = 'later') {
  const t = w.namer[k];
  if (mode & 1 && t >= 0) {
    const [i0, i1] = w.tris[t];
    const o = w.opposite[t];
    if (explicit[i0] && explicit[i1] && explicit[o]) return [0, 1, 2].map((i) => g(i0)[i] + g(i1)[i] - g(o)[i]);
  }
  const gate = t < 0 ? -1 : rule === 'later' ? Math.max(w.tris[t][0], w.tris[t][1]) : w.tris[t][0];
  let from = gate >= 0 && explicit[gate] ? gate : -1;
  if (from < 0) for (let c = k - 1; c >= 0 && from < 0; c--) if (explicit[c]) from = c;
  return from >= 0 ? g(from) : [0n, 0n, 0n];
}

/**
 * Zigzag residuals of the explicit corners (every x, then every y, then every z, in corner order)
 * that resolve to `target` (per corner its values; named corners' ignored).
 * @param {ReturnType<typeof walked>} w @param {boolean[]} explicit @param {number} mode @param {bigint[][]} target
 */
function encode13(w, explicit, mode, target) {
  /** @type {bigint[][]} */
  const out = [[], [], []];
  target.forEach((v, k) => {
    if (!explicit[k]) return;
    const p = predict(w, explicit, mode, k, (c) => target[c]);
    for (let i = 0; i < 3; i++) out[i].push(zigzag(v[i] - p[i]));
  });
  return out.flat();
}

/**
 * The reference decoding of zigzag residuals: the resolved values per corner (named corners
 * [0n, 0n, 0n]), or the error a reader must give.
 * @param {ReturnType<typeof walked>} w @param {boolean[]} explicit @param {number} mode @param {bigint[]} zz
 * @param {number[] | null} [sizes] with tables, each axis's count C @param {'later' | 'first'} [rule]
 * @returns {bigint[][] | 'BAD_GROUP_STRUCTURE'}
 */
function decode13(w, explicit, mode, zz, sizes = null, rule = 'later') {
  const V = w.namer.length;
  const E = explicit.filter(Boolean).length;
  /** @type {bigint[][]} */
  const g = [];
  for (let k = 0, e = 0; k < V; k++) {
    g.push([0n, 0n, 0n]);
    if (!explicit[k]) continue;
    const pred = predict(w, explicit, mode, k, (c) => g[c], rule);
    for (let i = 0; i < 3; i++) {
      const r = unzigzag(zz[i * E + e]);
      const v = pred[i] + r;
      if (r > Z || r < -Z || v > Z || v < -Z) return 'BAD_GROUP_STRUCTURE';
      if (sizes && (v < 0n || v >= BigInt(sizes[i]))) return 'BAD_GROUP_STRUCTURE';
      g[k][i] = v;
    }
    e++;
  }
  return g;
}

/**
 * Kind 13 (or 9) data: the walk's fields, the faces (per triangle a local reference, or -1 free),
 * the flags, the mode, an f32 grid, the tables (per axis its ascending values) where bit 1 of the
 * mode is set, the residuals. Mode, grid, tables and residuals only where a corner is explicit.
 * @param {Walk} w @param {number} mode @param {(number | bigint)[]} zz
 * @param {{tables?: number[][] | null, grid?: number[], faces?: number[] | null, explicit?: boolean[] | null}} [options]
 */
function body({ V, T, symbols, escapes }, mode, zz, { tables = null, grid = [0.5, -1, 2, 0.25], faces = null, explicit = null } = {}) {
  const flags = new Array(Math.ceil(V / 8)).fill(0);
  for (let k = 0; k < V; k++) if (!explicit || explicit[k]) flags[k >> 3] |= 1 << (k & 7);
  const E = explicit ? explicit.filter(Boolean).length : V;
  const tableBytes = tables ? tables.flatMap((t) => [...varint(t.length), ...varint(zigzag(BigInt(t[0]))), ...varints(t.slice(1).map((v, i) => v - t[i] - 1))]) : [];
  const faceCodes = faces ? faces.map((f) => (f < 0 ? 1 : f + 2)) : new Array(T).fill(1);
  return [...varints([V, T, escapes.length]), ...varints(symbols), ...varints(escapes), ...varints(faceCodes), ...flags,
    ...(E > 0 ? [mode, ...grid.flatMap(f32), ...tableBytes, ...varints(zz)] : [])];
}

/**
 * A fan of n corners round corner 0, each triangle attached across edge 2 (from its third corner
 * back to 0) of the one before: the root (0 1 2), then (0 2 3), (0 3 4) … Corner k ≥ 3 is named by
 * (0, k − 1, k), whose gate is (0, k − 1): kind 13 steps from k − 1, kind 9 from 0.
 * @param {number} n @returns {Walk}
 */
const fanBack = (n) => ({ V: n, T: n - 2, symbols: [3, ...new Array(n - 4).fill(8), 0], escapes: [0, 0, 0] });

/**
 * The fan of reflect.test.mjs, round corner 1, each triangle attached across edge 1: (0 1 2),
 * (2 1 3), (3 1 4) … Corner k ≥ 3 is named by (k − 1, 1, k), whose i0 = k − 1 is the later gate
 * corner already: kinds 9 and 13 agree.
 * @param {number} n @returns {Walk}
 */
const fanOn = (n) => ({ V: n, T: n - 2, symbols: [2, ...new Array(n - 4).fill(4), 0], escapes: [0, 0, 0] });

/**
 * A walk decoded from residuals given per corner as [x, y, z] (every corner explicit): its integer
 * coordinates (or table values), or the error.
 * @param {Walk} walk @param {(number | bigint)[][]} r @param {number} [mode] @param {number[][] | null} [tables]
 */
function decodeWalk(walk, r, mode = 0, tables = null, kind = 13) {
  const zz = [0, 1, 2].flatMap((i) => r.map((c) => zigzag(BigInt(c[i]))));
  const bytes = file([{ kind, data: body(walk, mode, zz, { tables }) }]);
  const o = outcome(bytes);
  return o === 'ok' ? shellOf(bytes).grid : o;
}

// ---------------------------------------------------------------------------------------------

test('§9.17 by hand: a fan whose gates are (0, k − 1) steps from k − 1, kind 9 from 0; the parallelogram unchanged', () => {
  assert.deepEqual(walked(fanBack(6)).tris, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]);
  const r = [[0, 0, 0], [4, 0, 0], [0, 3, 0], [-1, 0, 1], [0, -2, 0], [2, 2, 2]];
  // corners 1 and 2 (the root's) from the corner before; 3, 4, 5 from the later gate corner k − 1:
  // g3 = (4 3 0) + (−1 0 1) = (3 3 1), g4 = (3 1 1), g5 = (5 3 3)
  const steps = [[0, 0, 0], [4, 0, 0], [4, 3, 0], [3, 3, 1], [3, 1, 1], [5, 3, 3]];
  assert.deepEqual(decodeWalk(fanBack(6), r), steps);
  // kind 9 reads the same residuals from corner 0 (i0): another shape
  assert.deepEqual(decodeWalk(fanBack(6), r, 0, null, 9), [[0, 0, 0], [4, 0, 0], [4, 3, 0], [-1, 0, 1], [0, -2, 0], [2, 2, 2]]);
  // mode 1: the parallelogram g(i0) + g(i1) − g(o), o the parent's opposite corner, as in kind 9:
  // g3 = g0 + g2 − g1 + r3 = (−1 3 1), g4 = g0 + g3 − g2 + r4 = (−5 −2 1), g5 = g0 + g4 − g3 + r5 = (−2 −3 2)
  const grams = [[0, 0, 0], [4, 0, 0], [4, 3, 0], [-1, 3, 1], [-5, -2, 1], [-2, -3, 2]];
  assert.deepEqual(decodeWalk(fanBack(6), r, 1), grams);
  assert.deepEqual(decodeWalk(fanBack(6), r, 1, null, 9), grams);
  // the other fan: the naming triangle (k − 1, 1, k) has i0 = k − 1 > i1 = 1, so kinds 9 and 13 agree
  assert.deepEqual(walked(fanOn(5)).tris, [[0, 1, 2], [2, 1, 3], [3, 1, 4]]);
  const on = [[0, 0, 0], [3, 0, 0], [1, 2, 0], [5, 0, 0], [0, 0, -1]];
  assert.deepEqual(decodeWalk(fanOn(5), on), [[0, 0, 0], [3, 0, 0], [4, 2, 0], [9, 2, 0], [9, 2, -1]]);
  assert.deepEqual(decodeWalk(fanOn(5), on, 0, null, 9), decodeWalk(fanOn(5), on));
  // tables (mode 2): the same steps over indices; the corners take the tables' values
  const tables = [[-3, 0, 4, 9, 20, 21], [0, 1, 2, 3, 4], [10, 11, 12, 13]];
  assert.deepEqual(decodeWalk(fanBack(6), r, 2, tables), steps.map((c) => c.map((v, i) => tables[i][v])));
  // the corners on the grid at origin + step × coordinates
  const bytes = file([{ kind: 13, data: body(fanBack(6), 0, [0, 1, 2].flatMap((i) => r.map((c) => zigzag(BigInt(c[i]))))) }]);
  const pos = /** @type {NonNullable<ReturnType<typeof readNode>['meshes'][0]>} */ (readNode(bytes).meshes[0]).positions64;
  assert.deepEqual([...pos.subarray(15, 18)], [0.5 + 5 * 0.25, -1 + 3 * 0.25, 2 + 3 * 0.25]);
});

// ---------------------------------------------------------------------------------------------
// The cube, walked by an encoder written here (escapes for every third corner named before)

/** Walks of the cube: children in edge order (the gates' later corner always i0 but once) or reversed. */
const CUBE_WALKS = [{}, { reverse: true }, { reverse: true, rot: 1 }, { reverse: true, rot: 2 }, { start: 3, rot: 1 }];

/** The unit cube's planes as (ν, φ, h), local references 0-5: -z, +z, -y, +y, -x, +x. */
const CUBE_PLANES = [
  triplet([0, 0, -1], [0, 0, 0]), triplet([0, 0, 1], [0, 0, 1]), triplet([0, -1, 0], [0, 0, 0]),
  triplet([0, 1, 0], [0, 1, 0]), triplet([-1, 0, 0], [0, 0, 0]), triplet([1, 0, 0], [1, 0, 0]),
];
/** The unit cube, vertex v at (v & 1, v >> 1 & 1, v >> 2): twelve triangles on their face planes. */
const CUBE = {
  tris: [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]],
  face: [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5],
};

/**
 * §9.13's walk over triangles of source vertices: depth first from each triangle not reached yet,
 * children across every free edge whose neighbour is not claimed yet, in edge order (or reversed);
 * a third corner named before coded by an escape (code 3).
 * @param {number[][]} tris
 * @param {{start?: number, reverse?: boolean, rot?: number}} [options] start: the source triangle
 *   of the first root; reverse: children in reverse edge order; rot: a root's corners rotated
 */
function walkOf(tris, { start = 0, reverse = false, rot = 0 } = {}) {
  const T = tris.length;
  /** @type {Map<string, number>} */
  const across = new Map();
  tris.forEach((t, j) => { for (let e = 0; e < 3; e++) across.set(`${t[e]},${t[(e + 1) % 3]}`, j); });
  const claimed = new Uint8Array(T);
  /** @type {Map<number, number>} */
  const number = new Map();
  /** @type {number[]} corner → source vertex */
  const source = [];
  /** @type {number[]} walk triangle → source triangle */
  const order = [];
  /** @type {number[][]} */
  const out = [];
  /** @type {number[]} */
  const symbols = [];
  /** @type {number[]} */
  const escapes = [];
  /** @type {number[][]} [walk triangle, edge, source triangle] */
  const stack = [];
  const name = (/** @type {number} */ v) => { number.set(v, source.length); source.push(v); };
  /** claims the unclaimed neighbours across `free` edges of corners c: the children list */
  const children = (/** @type {number[]} */ c, /** @type {number[]} */ free) => (reverse ? [...free].reverse() : free).filter((e) => {
    const s = across.get(`${source[c[(e + 1) % 3]]},${source[c[e]]}`);
    if (s === undefined || claimed[s]) return false;
    claimed[s] = 1;
    return true;
  });
  let next = start;
  for (let j = 0; j < T; j++) {
    let c;
    let sym;
    /** @type {number[]} */
    let kids;
    if (stack.length === 0) {
      while (claimed[next]) next = (next + 1) % T;
      claimed[next] = 1;
      order.push(next);
      c = [0, 1, 2].map((i) => tris[next][(i + rot) % 3]).map((v) => {
        if (number.has(v)) {
          escapes.push(source.length - /** @type {number} */ (number.get(v)));
        } else {
          escapes.push(0);
          name(v);
        }
        return /** @type {number} */ (number.get(v));
      });
      kids = children(c, [0, 1, 2]);
      sym = ROOT_LISTS.indexOf(kids.join(''));
    } else {
      const [p, e, s] = /** @type {number[]} */ (stack.pop());
      order.push(s);
      const q = out[p];
      const [i0, i1] = [q[(e + 1) % 3], q[e]];
      const v = /** @type {number} */ (tris[s].find((u) => u !== source[i0] && u !== source[i1]));
      let k = 0;
      if (number.has(v)) {
        k = 3;
        const d = /** @type {number} */ (number.get(v)) - i1;
        escapes.push(d >= 0 ? 2 * d : -2 * d - 1);
      } else name(v);
      c = [i0, i1, /** @type {number} */ (number.get(v))];
      kids = children(c, [1, 2]);
      sym = 4 * ATTACHED_LISTS.indexOf(kids.join('')) + k;
    }
    out.push(c);
    symbols.push(sym);
    for (let q = kids.length - 1; q >= 0; q--) {
      const e = kids[q];
      stack.push([j, e, /** @type {number} */ (across.get(`${source[c[(e + 1) % 3]]},${source[c[e]]}`))]);
    }
  }
  return { walk: { V: source.length, T, symbols, escapes }, source, order, tris: out };
}

test('§9.17 with named corners: the cube in all 256 mixes of named and explicit corners, every mode, both rules', () => {
  let laterNamed = 0; // explicit corners whose later gate corner is named, the other explicit: from the previous explicit corner
  let laterOnly = 0; // explicit corners whose later gate corner is explicit, the other named: kind 9 would not step from it
  let differ = 0;
  for (const options of CUBE_WALKS) {
    const enc = walkOf(CUBE.tris, options);
    const w = walked(enc.walk);
    assert.deepEqual(w.tris, enc.tris);
    const faces = enc.order.map((s) => CUBE.face[s]);
    const coords = enc.source.map((v) => [v & 1, (v >> 1) & 1, v >> 2]);
    for (let set = 0; set < 256; set++) {
      const explicit = enc.source.map((v) => ((set >> v) & 1) === 1);
      const E = explicit.filter(Boolean).length;
      for (let k = 0; k < 8; k++) {
        const t = w.namer[k];
        if (!explicit[k] || t < 0) continue;
        const [i0, i1] = w.tris[t];
        const [early, late] = i0 < i1 ? [i0, i1] : [i1, i0];
        if (!explicit[late] && explicit[early]) laterNamed++;
        if (explicit[late] && !explicit[early]) laterOnly++;
      }
      for (const mode of E === 0 ? [0] : [0, 1, 2, 3]) {
        // with tables, each axis's values among the explicit corners (a table holds at most E)
        const tables = mode & 2 ? [0, 1, 2].map((i) => [...new Set(coords.filter((_, k) => explicit[k]).map((c) => c[i]))].sort()) : null;
        const target = coords.map((c) => c.map((v, i) => BigInt(tables ? tables[i].indexOf(v) : v)));
        const zz = encode13(w, explicit, mode, target);
        const sizes = tables && tables.map((t) => t.length);
        const want = decode13(w, explicit, mode, zz, sizes);
        assert.ok(Array.isArray(want));
        want.forEach((v, k) => explicit[k] && assert.deepEqual(v, target[k]));
        const first = decode13(w, explicit, mode, zz, sizes, 'first');
        if (JSON.stringify(first, (_, v) => (typeof v === 'bigint' ? Number(v) : v)) !== JSON.stringify(want, (_, v) => (typeof v === 'bigint' ? Number(v) : v))) differ++;
        const bytes = file([{ kind: 13, m: 6, data: body(enc.walk, mode, zz, { tables, grid: [0, 0, 0, 1], faces, explicit }) }], 2, CUBE_PLANES);
        const f = readNode(bytes);
        const report = conformanceJson(f);
        assert.deepEqual(conformanceJson(readBrowser(bytes)), report);
        const shell = report.groups[0].shell;
        assert.deepEqual(shell.explicit, explicit.flatMap((x, k) => (x ? [k] : [])));
        assert.deepEqual(shell.grid, coords.filter((_, k) => explicit[k]), `${JSON.stringify(options)} set ${set} mode ${mode}`);
        assert.deepEqual(shell.facets.map((/** @type {number[]} */ t) => t.slice(1)), enc.tris);
        // every corner, named or explicit, at its cube vertex
        const pos = /** @type {NonNullable<typeof f.meshes[0]>} */ (f.meshes[0]).positions64;
        coords.forEach((c, k) => c.forEach((v, i) => assert.ok(Math.abs(pos[3 * k + i] - v) < 1e-9, `set ${set} mode ${mode} corner ${k}`)));
      }
    }
  }
  assert.ok(laterNamed > 50 && laterOnly > 50, `${laterNamed} ${laterOnly}`);
  assert.ok(differ > 100, `${differ}`);
});

test('§9.17 by hand: a later gate corner named falls back to the previous explicit corner, not to i0', () => {
  // in the cube's walks, each corner k whose naming triangle's later gate corner `late` can be named
  // while the corner before k in corner order (the previous explicit one) is not the other gate
  // corner: with every corner but `late` explicit and residual 0, k lands on that previous corner
  // (not on i0, which kind 9 steps from); with every corner explicit, on `late`
  let checked = 0;
  let laterI1 = 0; // of them, those whose i1 is the later: i0 explicit, yet not stepped from
  for (const options of CUBE_WALKS) {
    const enc = walkOf(CUBE.tris, options);
    const w = walked(enc.walk);
    const coords = enc.source.map((v) => [v & 1, (v >> 1) & 1, v >> 2]);
    const faces = enc.order.map((s) => CUBE.face[s]);
    const target = coords.map((c) => c.map(BigInt));
    for (let k = 3; k < 8; k++) {
      const t = w.namer[k];
      if (t < 0) continue;
      const [i0, i1] = w.tris[t];
      const late = Math.max(i0, i1);
      const prev = late === k - 1 ? k - 2 : k - 1;
      if (prev === Math.min(i0, i1)) continue;
      const explicit = coords.map((_, c) => c !== late);
      const zz = encode13(w, explicit, 0, target);
      const e = explicit.slice(0, k).filter(Boolean).length;
      for (let i = 0; i < 3; i++) zz[i * 7 + e] = 0n;
      const data = body(enc.walk, 0, zz, { grid: [0, 0, 0, 1], faces, explicit });
      assert.deepEqual(shellOf(file([{ kind: 13, m: 6, data }], 2, CUBE_PLANES)).grid[e], coords[prev], `corner ${k}: from the previous explicit corner ${prev}`);
      const all = coords.map(() => true);
      const zzAll = encode13(w, all, 0, target);
      for (let i = 0; i < 3; i++) zzAll[i * 8 + k] = 0n;
      const dataAll = body(enc.walk, 0, zzAll, { grid: [0, 0, 0, 1], faces, explicit: all });
      assert.deepEqual(shellOf(file([{ kind: 13, m: 6, data: dataAll }], 2, CUBE_PLANES)).grid[k], coords[late], `corner ${k}: from its later gate corner ${late}`);
      // kind 9 reads the same bytes from i0 where it is explicit (and so every corner by its rule)
      if (i1 > i0) {
        laterI1++;
        const grid9 = shellOf(file([{ kind: 9, m: 6, data }], 2, CUBE_PLANES)).grid;
        assert.deepEqual(grid9[e], grid9[explicit.slice(0, i0).filter(Boolean).length], `corner ${k}: kind 9 from i0 ${i0}`);
        const first = /** @type {bigint[][]} */ (decode13(w, explicit, 0, zz, null, 'first'));
        assert.deepEqual(grid9, first.filter((_, c) => explicit[c]).map((v) => v.map(Number)));
      }
      checked++;
    }
  }
  assert.ok(checked > 10 && laterI1 > 3, `${checked} ${laterI1}`);
});

// ---------------------------------------------------------------------------------------------
// Golden walks

/**
 * The fields of the first walk group of a golden file (kind 9, 10, 12 or 13, every corner explicit),
 * read here from its body, and its decoded report.
 * @param {string} name
 */
function goldenWalk(name) {
  const bytes = golden(name);
  const f = readNode(bytes);
  const index = f.container.groups.findIndex((g) => [9, 10, 12, 13].includes(g.kind));
  const { kind, body: raw } = groupBody(bytes, index, f);
  const b = new Cursor(raw);
  const m = b.varint();
  for (let i = 0; i < m; i++) b.varint();
  b.take(Math.ceil(m / 8));
  const [V, T, X] = [b.varint(), b.varint(), b.varint()];
  const read = (/** @type {number} */ n) => Array.from({ length: n }, () => b.varint());
  const symbols = read(T);
  const escapes = read(X);
  read(T);
  assert.ok([...b.take(Math.ceil(V / 8))].every((byte, i) => byte === (i < V >> 3 ? 0xff : (1 << (V & 7)) - 1)), 'every corner explicit');
  const mode = b.u8();
  b.take(f.version[0] >= 5 ? 16 : 32);
  /** @type {number[][]} per axis its values */
  const tables = [];
  if (mode & 2) {
    for (let i = 0; i < 3; i++) {
      const C = b.varint();
      let v = Number(unzigzag(BigInt(b.varint())));
      const values = [v];
      for (const gap of read(C - 1)) values.push((v += gap + 1));
      tables.push(values);
    }
  }
  const zz = Array.from({ length: 3 * V }, () => bigVarint(b));
  assert.equal(b.left, 0);
  const shell = conformanceJson(f).groups[index].shell;
  return { walk: { V, T, symbols, escapes }, kind, mode, tables: mode & 2 ? tables : null, zz, grid: /** @type {number[][]} */ (shell.grid), tris: shell.facets.map((/** @type {number[]} */ t) => t.slice(1)) };
}

const WALKS = ['shell_walk_sphere_v4_1.pln', 'shell_walk_torus_v4_1.pln', 'scene_up_axis_v5_0.pln', 'shell_walk_reflect_knot_v5_1.pln',
  'shell_walk_reflect_far_v5_1.pln', 'shell_walk_later_values_v5_2.pln'];
/** @param {bigint[][] | string} g @param {number[][] | null} tables */
const valuesOf = (g, tables) => (typeof g === 'string' ? g : g.map((v) => v.map((x, i) => (tables ? tables[i][Number(x)] : Number(x)))));

test('§9.17: the 5.2 golden files decoded by the reference as by the reader; kind 9\'s rule decodes another shape', () => {
  for (const name of ['shell_walk_later_values_v5_2.pln', 'shell_walk_later_tables_v5_2.pln']) {
    const g = goldenWalk(name);
    assert.equal(g.kind, 13);
    const w = walked(g.walk);
    const explicit = new Array(g.walk.V).fill(true);
    const sizes = g.tables && g.tables.map((t) => t.length);
    assert.deepEqual(valuesOf(decode13(w, explicit, g.mode, g.zz, sizes), g.tables), g.grid, name);
    // kind 9's rule: another shape in mode 0 and 2; with mode bit 0 and every corner explicit, each
    // corner an attached triangle names has its parallelogram, and the rules agree
    const first = valuesOf(decode13(w, explicit, g.mode, g.zz, sizes, 'first'), g.tables);
    if (g.mode & 1) assert.deepEqual(first, g.grid, name);
    else assert.notDeepEqual(first, g.grid, name);
    assert.deepEqual(shellOf(golden(name)).json.header.version, [5, 2]);
  }
});

test('§9.17 round trips: the walks of six golden files (spheres, tori) as kind 13 in every mode; kind 9 reads them otherwise', () => {
  let steppedLater = 0;
  let corners = 0;
  let differ = 0;
  for (const name of WALKS) {
    const g = goldenWalk(name);
    const w = walked(g.walk);
    const explicit = new Array(g.walk.V).fill(true);
    // the corners whose naming triangle's later gate corner is i1: there the rules differ
    let later = 0;
    for (let k = 0; k < g.walk.V; k++) {
      const t = w.namer[k];
      if (t >= 0 && w.tris[t][1] > w.tris[t][0]) later++;
    }
    steppedLater += later;
    corners += g.walk.V;
    for (const mode of [0, 1, 2, 3]) {
      /** @type {number[][] | null} */
      const tables = mode & 2 ? [0, 1, 2].map((i) => [...new Set(g.grid.map((c) => c[i]))].sort((p, q) => p - q)) : null;
      const target = g.grid.map((c) => c.map((v, i) => BigInt(tables ? tables[i].indexOf(v) : v)));
      const zz = encode13(w, explicit, mode, target);
      const sizes = tables && tables.map((t) => t.length);
      assert.deepEqual(decode13(w, explicit, mode, zz, sizes), target);
      const data = body(g.walk, mode, zz, { tables });
      const s = shellOf(file([{ kind: 13, data }]));
      assert.deepEqual(s.grid, g.grid, `${name} mode ${mode}`);
      assert.deepEqual(s.tris, g.tris, `${name} mode ${mode}`);
      assert.equal(s.json.groups[0].kind, 13);
      assert.deepEqual(s.json.header.version, [5, 2]);
      assert.deepEqual(s.json.findings, []);
      // the same bytes as kind 9: §9.11's predictor (i0) where kind 13 steps from max(i0, i1): another
      // shape where some corner's i1 is the later (the sphere of shell_walk_sphere_v4_1 was walked
      // with i0 the later everywhere: the same there); with mode bit 0 every corner an attached
      // triangle names has its parallelogram (all explicit), and the roots' corners step from the
      // previous one in both kinds: the same shape
      const as9 = file([{ kind: 9, data }]);
      const first = valuesOf(decode13(w, explicit, mode, zz, sizes, 'first'), tables);
      if (typeof first === 'string') assert.equal(outcome(as9), first);
      else assert.deepEqual(shellOf(as9).grid, first);
      if (mode & 1 || later === 0) assert.deepEqual(first, g.grid, `${name} mode ${mode}: the same shape`);
      else {
        assert.notDeepEqual(first, g.grid, `${name} mode ${mode}: kind 9's rule decodes another shape`);
        differ++;
      }
    }
  }
  // a good share of the corners have a later i1 (where the rules differ)
  assert.ok(steppedLater > 0.2 * corners, `${steppedLater} of ${corners}`);
  assert.ok(differ >= 8, `${differ}`);
});

// ---------------------------------------------------------------------------------------------
// Hostile bodies

test('§9.13 via §9.17: a mode with a bit above 1 set is BAD_GROUP_STRUCTURE', () => {
  const r = [[0, 0, 0], [4, 0, 0], [0, 3, 0], [-1, 0, 1], [0, -2, 0], [2, 2, 2]];
  for (const mode of [4, 5, 6, 7, 8, 0x10, 0x20, 0x40, 0x80, 0xfc, 0xff]) {
    const tables = mode & 2 ? [[0, 1, 2, 3, 4, 5], [0, 1, 2, 3, 4, 5], [0, 1, 2, 3]] : null;
    assert.equal(decodeWalk(fanBack(6), r, mode, tables), 'BAD_GROUP_STRUCTURE', `mode ${mode}`);
  }
  for (const mode of [0, 1]) assert.ok(Array.isArray(decodeWalk(fanBack(6), r, mode)));
});

test('§9.17 hostile: tables: an index the later gate corner puts past its table or below 0', () => {
  // x indices step from k − 1: 0, 1, 2, 3, 4 (residuals 1 each), table of 5: corner 5 at 5 is past it
  const tables = [[-7, -2, 0, 3, 8], [1, 2], [0]];
  const r = (/** @type {number} */ x5) => [[0, 0, 0], [1, 0, 0], [1, 1, 0], [1, 0, 0], [1, 0, 0], [x5, 0, 0]];
  assert.deepEqual(decodeWalk(fanBack(6), r(0), 2, tables), [[-7, 1, 0], [-2, 1, 0], [0, 2, 0], [3, 2, 0], [8, 2, 0], [8, 2, 0]]);
  assert.equal(decodeWalk(fanBack(6), r(1), 2, tables), 'BAD_GROUP_STRUCTURE');
  assert.deepEqual(decodeWalk(fanBack(6), r(-4), 2, tables)[5], [-7, 2, 0]);
  assert.equal(decodeWalk(fanBack(6), r(-5), 2, tables), 'BAD_GROUP_STRUCTURE');
  // kind 9 steps corner 5 from corner 0 (index 0): x residual 4 is in its table there, past it here
  assert.deepEqual(decodeWalk(fanBack(6), r(4), 2, tables, 9)[5], [8, 1, 0]);
  assert.equal(decodeWalk(fanBack(6), r(4), 2, tables), 'BAD_GROUP_STRUCTURE');
  // y past a table of 2, z below a table of 1; mode 3 (corners 3-5 by parallelograms)
  assert.equal(decodeWalk(fanBack(6), [...r(0).slice(0, 5), [0, 1, 0]], 2, tables), 'BAD_GROUP_STRUCTURE');
  assert.equal(decodeWalk(fanBack(6), [...r(0).slice(0, 5), [0, 0, -1]], 2, tables), 'BAD_GROUP_STRUCTURE');
  assert.equal(decodeWalk(fanBack(6), [...r(0).slice(0, 5), [-Z, 0n, 0n]], 2, tables), 'BAD_GROUP_STRUCTURE');
  // mode 3: corners 3-5 by parallelograms over indices, g(i0) + g(i1) − g(o): corner 3 at x 0 + 2 − 1 + 1
  // = 2, y 0 + 1 − 0 = 1; corner 4 at x 0 + 2 − 2 + 1 = 1, y 0; corner 5 at x 0 + 1 − 2 = −1 (below its
  // table) and y 0 + 0 − 1 = −1 before their residuals: some residuals bring them back, others not
  const w6 = walked(fanBack(6));
  const all = new Array(6).fill(true);
  const seen = new Set();
  for (const x5 of [-1, 0, 1, 2, 4, 5]) {
    for (const y5 of [0, 1, 2, 3]) {
      const rr = [...r(0).slice(0, 5), [x5, y5, 0]];
      const want = valuesOf(decode13(w6, all, 3, [0, 1, 2].flatMap((i) => rr.map((c) => zigzag(BigInt(c[i])))), tables.map((t) => t.length)), tables);
      assert.deepEqual(decodeWalk(fanBack(6), rr, 3, tables), want, `${x5} ${y5}`);
      seen.add(typeof want === 'string' ? want : 'ok');
      if (x5 === 1 && y5 === 1) assert.deepEqual(want, [[-7, 1, 0], [-2, 1, 0], [0, 2, 0], [0, 2, 0], [-2, 1, 0], [-7, 1, 0]]);
    }
  }
  assert.deepEqual([...seen].sort(), ['BAD_GROUP_STRUCTURE', 'ok']);
});

test('§9.17 hostile: values past 2^52 stepping from the later gate corner, residuals past it', () => {
  const z = Number(Z);
  // x: corner 0 at 2^52 − 3, each corner one further from k − 1: corner 3 at 2^52, corner 4 past it
  const head = [[Z - 3n, 0n, 0n], [1n, 0n, 0n], [1n, 0n, 0n], [1n, 0n, 0n]];
  assert.deepEqual(decodeWalk(fanBack(6), [...head, [0n, 0n, 0n], [0n, 0n, 0n]]).slice(3), [[z, 0, 0], [z, 0, 0], [z, 0, 0]]);
  assert.equal(decodeWalk(fanBack(6), [...head, [1n, 0n, 0n], [-5n, 0n, 0n]]), 'BAD_GROUP_STRUCTURE');
  // kind 9 steps corner 4 from corner 0: the same residual 1 stays within 2^52
  assert.deepEqual(decodeWalk(fanBack(6), [...head, [1n, 0n, 0n], [-5n, 0n, 0n]], 0, null, 9).slice(4), [[z - 2, 0, 0], [z - 8, 0, 0]]);
  // the mirror image, toward −2^52
  const low = [[-Z + 3n, 0n, 0n], [-1n, 0n, 0n], [-1n, 0n, 0n], [-1n, 0n, 0n]];
  assert.deepEqual(decodeWalk(fanBack(6), [...low, [0n, 0n, 0n], [0n, 0n, 0n]])[5], [-z, 0, 0]);
  assert.equal(decodeWalk(fanBack(6), [...low, [0n, 0n, 0n], [-1n, 0n, 0n]]), 'BAD_GROUP_STRUCTURE');
  // a residual past 2^52 whose value would be within it: the residual decides
  assert.equal(decodeWalk(fanBack(6), [[Z, 0n, 0n], [0n, 0n, 0n], [0n, 0n, 0n], [-Z - 1n, 0n, 0n], [0n, 0n, 0n], [0n, 0n, 0n]]), 'BAD_GROUP_STRUCTURE');
  assert.deepEqual(decodeWalk(fanBack(6), [[Z, 0n, 0n], [0n, 0n, 0n], [0n, 0n, 0n], [-Z, 0n, 0n], [0n, 0n, 0n], [0n, 0n, 0n]])[3], [0, 0, 0]);
  // from 2^52 at corner 2 to −2^52 at corner 3 (a step of 2^53, its residual past 2^52)
  assert.equal(decodeWalk(fanBack(6), [[0n, 0n, 0n], [Z, 0n, 0n], [0n, 0n, 0n], [-2n * Z, 0n, 0n], [0n, 0n, 0n], [0n, 0n, 0n]]), 'BAD_GROUP_STRUCTURE');
  // mode 1: a parallelogram past 2^52 (g0 + g2 − g1 = 2^52 + 2^52 − 0), brought back by its residual
  const gram = (/** @type {bigint} */ r3) => decodeWalk(fanBack(6), [[Z, 0n, 0n], [-Z, 0n, 0n], [Z, 0n, 0n], [r3, 0n, 0n], [0n, 0n, 0n], [0n, 0n, 0n]], 1);
  assert.deepEqual(/** @type {number[][]} */ (gram(-Z))[3], [z, 0, 0]);
  assert.equal(gram(-Z + 1n), 'BAD_GROUP_STRUCTURE');
  // the largest varint (2^64 − 1, zigzag −2^63) as the residual of a corner stepping from k − 1
  const zz = [0, 1, 2].flatMap((i) => [[0n, 0n, 0n], [0n, 1n, 0n], [1n, 1n, 0n], [0n, 0n, 0n]].map((c) => zigzag(c[i])));
  zz[3] = 2n ** 64n - 1n;
  assert.equal(outcome(file([{ kind: 13, data: body(fanBack(4), 0, zz) }])), 'BAD_GROUP_STRUCTURE');
});

test('§9.17 hostile: random residual sets near ±2^52 against the reference, in every mode', () => {
  let seed = 1313;
  const rnd = () => {
    seed = (Math.imul(seed, 1103515245) + 12345) >>> 0;
    return seed / 4294967296;
  };
  const walks = [fanBack(12), goldenWalk('shell_walk_torus_v4_1.pln').walk, goldenWalk('shell_walk_sphere_v4_1.pln').walk];
  const outcomes = { ok: 0, bad: 0 };
  for (const fields of walks) {
    const w = walked(fields);
    const V = fields.V;
    const explicit = new Array(V).fill(true);
    for (const mode of [0, 1, 2, 3]) {
      for (let trial = 0; trial < 16; trial++) {
        const sizes = [3 + Math.floor(rnd() * V), 1 + Math.floor(rnd() * V), 2 + Math.floor(rnd() * V)].map((s) => Math.min(s, V));
        const base = [Z - 50n, -Z + 50n, 0n][trial % 3];
        /** @type {bigint[][]} */
        const g = [];
        const zz = new Array(3 * V);
        for (let k = 0; k < V; k++) {
          const pred = predict(w, explicit, mode, k, (c) => g[c]);
          g.push([0n, 0n, 0n]);
          for (let i = 0; i < 3; i++) {
            let target;
            if (mode & 2) {
              target = BigInt(Math.floor(rnd() * (sizes[i] + (trial % 4 === 0 ? 1 : 0))) - (rnd() < 0.01 ? 1 : 0));
            } else {
              const u = rnd();
              target = u < 0.85 ? base + BigInt(Math.floor(rnd() * 121) - 60) : u < 0.95 ? BigInt(Math.floor((rnd() * 2 - 1) * 2 ** 52)) : (rnd() < 0.5 ? Z + 1n : -Z - 1n);
            }
            let r = target - pred[i];
            if (r > Z) r = Z;
            if (r < -Z) r = -Z;
            zz[i * V + k] = zigzag(r);
            g[k][i] = pred[i] + r;
          }
        }
        const want = decode13(w, explicit, mode, zz, mode & 2 ? sizes : null);
        const tables = mode & 2 ? sizes.map((s, i) => Array.from({ length: s }, (_, q) => 3 * q - i)) : null;
        const bytes = file([{ kind: 13, data: body(fields, mode, zz, { tables }) }]);
        if (want === 'BAD_GROUP_STRUCTURE') {
          assert.equal(outcome(bytes), want, `mode ${mode} trial ${trial}`);
          assert.equal(outcome(bytes, readBrowser), want);
          outcomes.bad++;
          continue;
        }
        outcomes.ok++;
        assert.deepEqual(shellOf(bytes).grid, valuesOf(want, tables), `mode ${mode} trial ${trial}`);
      }
    }
  }
  assert.ok(outcomes.ok > 20 && outcomes.bad > 20, JSON.stringify(outcomes));
});

test('§9.17 hostile: every prefix and many one-byte changes of a body are read or refused with a PlnError', () => {
  const g = goldenWalk('shell_walk_torus_v4_1.pln');
  const w = walked(g.walk);
  const explicit = new Array(g.walk.V).fill(true);
  const data = body(g.walk, 0, encode13(w, explicit, 0, g.grid.map((c) => c.map(BigInt))));
  const codes = new Set();
  for (let n = 0; n < data.length; n++) codes.add(outcome(file([{ kind: 13, data: data.slice(0, n) }])));
  assert.deepEqual([...codes].sort(), ['BAD_GROUP_STRUCTURE', 'BAD_PAYLOAD']);
  let seed = 1717;
  const rnd = () => {
    seed = (Math.imul(seed, 1103515245) + 12345) >>> 0;
    return seed / 4294967296;
  };
  const seen = new Set();
  for (let trial = 0; trial < 1500; trial++) {
    const d = data.slice();
    d[Math.floor(rnd() * d.length)] = Math.floor(rnd() * 256);
    seen.add(outcome(file([{ kind: 13, data: d }])));
  }
  assert.ok(seen.has('ok') && seen.has('BAD_GROUP_STRUCTURE'), [...seen].join());
});

// ---------------------------------------------------------------------------------------------
// Versions

test('§9.3, §13: kind 13 in 5.2 and later minors, unknown in 5.0 and 5.1; kind 14 unknown in 5.2, skipped in 5.3', () => {
  const r = [[0, 0, 0], [4, 0, 0], [0, 3, 0], [-1, 0, 1], [0, -2, 0], [2, 2, 2]];
  const data = body(fanBack(6), 0, [0, 1, 2].flatMap((i) => r.map((c) => zigzag(BigInt(c[i])))));
  const grid = decodeWalk(fanBack(6), r);
  for (const read of [readNode, readBrowser]) {
    assert.equal(outcome(file([{ kind: 13, data }], 1), read), 'UNKNOWN_GROUP_KIND');
    assert.equal(outcome(file([{ kind: 13, data }], 0), read), 'UNKNOWN_GROUP_KIND');
    assert.equal(outcome(file([{ kind: 14, data }], 2), read), 'UNKNOWN_GROUP_KIND');
    assert.deepEqual([...read(file([{ kind: 13, data }], 2)).findings], []);
  }
  // 5.3: kind 13 read (a newer minor, MAY be reported), kind 14 skipped with its common body checked
  const newer = readNode(file([{ kind: 13, data }], 3));
  assert.deepEqual([...newer.findings], ['NEWER_MINOR_VERSION']);
  assert.deepEqual(conformanceJson(newer).groups[0].shell.grid, grid);
  const skipped = readNode(file([{ kind: 14, data }, { kind: 13, data }], 3));
  assert.deepEqual([...skipped.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  assert.equal(skipped.meshes[0], null);
  assert.deepEqual(conformanceJson(skipped).groups[0], { index: 0, object: 0, kind: 14, refs: [], bounding: [] });
  assert.deepEqual(conformanceJson(skipped).groups[1].shell.grid, grid);
  assert.deepEqual([...readBrowser(file([{ kind: 14, data: [1, 2, 3] }], 3)).findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  // kind 14's common body is still checked: a reference to no plane
  assert.equal(outcome(file([{ kind: 14, data: [], m: 1 }], 3)), 'BAD_PLANE_REFERENCE');
  // the header's version
  assert.deepEqual(conformanceJson(readNode(file([{ kind: 13, data }]))).header.version, [5, 2]);
});

test('§9.2, §9.15: kind 13 without references or on face planes; copied; a copy of a skipped kind 14 skipped; named in the loader', () => {
  const r = [[0, 0, 0], [4, 0, 0], [0, 3, 0], [-1, 0, 1], [0, -2, 0], [2, 2, 2]];
  const zz = [0, 1, 2].flatMap((i) => r.map((c) => zigzag(BigInt(c[i]))));
  const data = body(fanBack(6), 0, zz);
  // on one plane (local reference 0) for every triangle: the same corners
  const one = [triplet([0, 0, 1], [0, 0, 0])];
  const onPlane = file([{ kind: 13, m: 1, data: body(fanBack(6), 0, zz, { faces: [0, 0, 0, 0] }) }], 2, one);
  assert.deepEqual(shellOf(onPlane).grid, decodeWalk(fanBack(6), r));
  assert.deepEqual(shellOf(onPlane).json.groups[0].shell.facets.map((/** @type {number[]} */ t) => t[0]), [0, 0, 0, 0]);
  // a copy (kind 11, source 0, no references) of a kind 13 group: its surface
  const bytes = file([{ kind: 13, data }, { kind: 11, data: [0] }]);
  const f = readNode(bytes);
  const [a, b] = /** @type {NonNullable<typeof f.meshes[0]>[]} */ (f.meshes);
  assert.equal(b.source, 0);
  assert.deepEqual([...b.positions64], [...a.positions64]);
  assert.deepEqual(conformanceJson(f).groups[1], { index: 1, object: 0, kind: 11, refs: [], bounding: [], source: 0 });
  // a copy of a kind 14 group in 5.3: skipped too (§9.15 step 3)
  const copied = readNode(file([{ kind: 14, data }, { kind: 11, data: [0] }], 3));
  assert.deepEqual(copied.meshes, [null, null]);
  // the three.js loader names the kind
  assert.equal(KIND_NAMES[13], 'shell walk from the later gate corner');
  const scene = new PLNLoader().parse(bytes);
  assert.deepEqual(scene.userData.groups.map((/** @type {{kindName: string}} */ g) => g.kindName), ['shell walk from the later gate corner', 'copy']);
});

test('§9.17: linear time on a fan of 200,000 corners each stepping from the one before', (t) => {
  const n = 200002;
  const zz = new Array(3 * n).fill(0n);
  for (let k = 1; k < n; k++) zz[k] = 2n; // x + 1 from the corner before
  const bytes = file([{ kind: 13, data: body(fanBack(n), 0, zz) }]);
  const t0 = performance.now();
  const grid = conformanceJson(readNode(bytes)).groups[0].shell.grid;
  const ms = performance.now() - t0;
  t.diagnostic(`read and reported in ${ms.toFixed(0)} ms`);
  assert.deepEqual(grid[n - 1], [n - 1, 0, 0]);
  assert.ok(ms < HANG_MS, `${ms} ms`);
});

test('the 5.2 conformance cases through both entries', () => {
  const cases = manifest().filter(([name]) => /_v5_2\.pln$|\/xv52_/.test(name));
  assert.ok(cases.length >= 5, `${cases.length} cases`);
  for (const [name, expected] of cases) {
    const bytes = suiteFile(name);
    expectListed(bytes, expected, name);
    if (expected === 'ok') {
      const json = caseJson(name);
      assert.deepEqual(conformanceJson(readNode(bytes)).groups, json.groups, name);
    }
  }
});

test('planefmt\'s kind 13 groups of the corpus decode here to its decoding, corner by corner', { skip: !available && 'no .venv or corpus' }, (t) => {
  let groups = 0;
  for (const rel of ['cad/ADIS16480.STL', 'cad/featuretype.STL', 'cad/box.STL']) {
    const name = encoded(rel);
    const f = readNode(fs.readFileSync(name));
    const k13 = f.container.groups.filter((g) => g.kind === 13).length;
    t.diagnostic(`${rel}: version ${f.version.join('.')}, ${k13} kind 13 group(s)`);
    if (k13 === 0) continue;
    groups += k13;
    const mine = f.mesh();
    const { positions, indices } = planefmtDecoding(name);
    // a shell's corners and triangles are as stored (§9.10): the same vertices in the same order
    assert.equal(mine.positions64.length, positions.length, rel);
    assert.deepEqual([...mine.indices], [...indices], rel);
    positions.forEach((v, i) => assert.ok(Math.abs(v - mine.positions64[i]) <= 1e-12 * Math.max(1, Math.abs(v)), `${rel} coordinate ${i}`));
  }
  assert.ok(groups > 0, 'planefmt wrote no kind 13 group for the CAD parts §9.17 names');
});
