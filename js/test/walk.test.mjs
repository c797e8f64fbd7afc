// Shell walks (kind 9, spec §9.13, version 4.1) on files made here: a walk encoder written for this
// test from §9.13's text (its open edges a plain list searched from the newest end, not the reader's
// hash table and linked lists) encodes meshes, which must decode to their triangles and corners, and
// to what the same triangles decode to as a shell tree (kind 7, or kind 8 with the parallelogram
// bit); hand-built bodies for every error of §9.13, in the order the section gives; the versions
// (kind 9 in 4.1 and later, kind 10 in 4.2 and later); linear time on hostile walks. Kind 10
// (§9.14, version 4.2): the same encoder's walks with the multi-parallelogram prediction (written
// here from §9.14 in BigInt), round trips in every mode, hand-computed predictions, and values
// near and past 2^52 against a reference decoding in BigInt.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import { readPln as readNode } from '../src/node.mjs';
import { readPln as readBrowser } from '../src/browser.mjs';
import { conformanceJson } from '../src/report.mjs';
import { OpenEdges } from '../src/shellwalk.mjs';
import { varint, varints, zigzag as zigzagBig, unzigzag as unzigzagBig, f64, common, file4, triplet, outcome, HANG_MS } from './files.mjs';

/** @param {number} d */
const zigzag = (d) => (d >= 0 ? 2 * d : -2 * d - 1);

/**
 * A file of version major.minor (3 or 4; 4.1 by default): float64 planes (ν, φ, h), one object,
 * groups of the given kinds and kind data, all referencing every plane (roles: `bounding` local
 * indices), stored with method 0, 1 or 2 (files.mjs's file4).
 * @param {{planes: number[][], groups: {kind: number, data: number[], bounding?: number[], method?: number}[], version?: [number, number]}} f
 */
function file({ planes, groups, version = [4, 1] }) {
  const refs = planes.map((_, i) => i);
  return file4({ planes: planes.flat(), version, groups: groups.map(({ kind, data, bounding = [], method = 0 }) => ({ kind, method, body: [...common(refs, bounding), ...data] })) });
}

// ---------------------------------------------------------------------------------------------
// The encoder: a mesh to kind 9 data (and the same triangles as kind 7 or 8 data), from §9.13.

const ROOT_LISTS = ['', '0', '1', '2', '01', '02', '10', '12', '20', '21', '012', '021', '102', '120', '201', '210'];
const ATTACHED_LISTS = ['', '1', '2', '12', '21'];

/**
 * @typedef {object} Mesh
 * @property {number[][]} tris source vertices of each triangle, counter-clockwise
 * @property {number[]} face local face reference of each triangle, -1 free
 * @property {(number[] | null)[]} coords per source vertex its integer coordinates (explicit), or null (named)
 * @property {Map<number, number[]>} [picks] per named source vertex on more than three planes, its picks
 */

/**
 * The walk of §9.13 over a mesh: depth first from each triangle not yet reached (as given, its
 * corners in order), children across every free edge whose neighbour is not reached yet, in edge
 * order or reversed; each third corner named before coded left or right where that names it.
 * @param {Mesh} mesh
 * @param {{mode?: number, reverse?: boolean, rotate?: number, grid?: number[], escapeAll?: boolean, drop?: number, oneChild?: boolean}} [options]
 *   mode: §9.13's mode byte; reverse: children in reverse edge order; rotate: the lists of a root
 *   rotated; escapeAll: code every third corner named before by its number (no left or right);
 *   drop: a seed: about a third of the children left out (reached later as roots over old corners);
 *   oneChild: an attached triangle whose third corner is new claims one child only, the other
 *   neighbour left to be reached around the corner (Edgebreaker's C), which keeps the open edges a
 *   simple loop so that left and right name nearly every third corner named before
 */
function encode(mesh, { mode = 0, reverse = false, rotate = 0, grid = [0.5, -1, 2, 0.25], escapeAll = false, drop = 0, oneChild = false } = {}) {
  let seed = drop;
  const rnd = () => {
    seed = (Math.imul(seed, 1103515245) + 12345) >>> 0;
    return seed / 4294967296;
  };
  let seconds = 0; // left or right answered by the second newest edge
  const T = mesh.tris.length;
  /** @type {Map<string, number>} directed edge → the triangle holding it */
  const across = new Map();
  mesh.tris.forEach((t, j) => { for (let e = 0; e < 3; e++) across.set(`${t[e]},${t[(e + 1) % 3]}`, j); });
  const reached = new Uint8Array(T);
  /** @type {{tri: number[], parent: number, edge: number, src: number}[]} the walk's triangles, corners as source vertices */
  const order = [];
  /** @type {number[]} */
  const symbols = [];
  /** @type {number[]} */
  const escapes = [];
  /** @type {number[]} links and corner codes of the same triangles as a shell tree (§9.11) */
  const links = [];
  /** @type {number[]} */
  const codes7 = [];
  /** @type {Map<number, number>} source vertex → corner */
  const corner = new Map();
  /** @type {number[]} corner → source vertex */
  const source = [];
  /** @type {number[]} per corner the walk triangle that named it anew, -1 for a root's */
  const namer = [];
  /** @type {number[][]} the open edges, oldest first */
  const open = [];
  const name = (/** @type {number} */ v, /** @type {number} */ j) => {
    corner.set(v, source.length);
    source.push(v);
    namer.push(j);
  };
  /**
   * Left (at 1: the start of the newest open edge ending at c) or right (at 0: the end of the newest
   * starting at c), the second newest where the newest's other end is `not`; whether that is `want`.
   * @param {number} c @param {number} not @param {0 | 1} at @param {number} want
   */
  const lookup = (c, not, at, want) => {
    let second = 0;
    for (let i = open.length - 1; i >= 0; i--) {
      if (open[i][at] !== c) continue;
      const w = open[i][1 - at];
      if (second === 0 && w === not) { second = 1; continue; }
      if (w === want) seconds += second;
      return w === want;
    }
    return false;
  };
  /** @type {{src: number, parent: number, edge: number}[]} slots */
  const stack = [];
  for (let root = 0; root < T || stack.length > 0;) {
    let src;
    let tri;
    let parent = -1;
    let edge = -1;
    const j = order.length;
    if (stack.length === 0) {
      if (reached[root]) { root++; continue; }
      src = root;
      reached[src] = 1;
      const codes = [];
      for (let s = 0; s < 3; s++) {
        const v = mesh.tris[src][s];
        if (corner.has(v)) codes.push(source.length - /** @type {number} */ (corner.get(v)));
        else { codes.push(0); name(v, -1); }
      }
      escapes.push(...codes);
      links.push(0);
      codes7.push(...codes);
      tri = mesh.tris[src].map((v) => /** @type {number} */ (corner.get(v)));
    } else {
      const slot = /** @type {{src: number, parent: number, edge: number}} */ (stack.pop());
      ({ src, parent, edge } = slot);
      const q = order[parent].tri;
      const i0 = q[(edge + 1) % 3];
      const i1 = q[edge];
      const x = q[(edge + 2) % 3];
      // the source triangle turned so that it starts at i0, i1
      const t = mesh.tris[src];
      const r = t.findIndex((v, s) => corner.get(v) === i0 && corner.get(t[(s + 1) % 3]) === i1);
      assert.ok(r >= 0, 'a child shares its parent edge the other way round');
      const v2 = t[(r + 2) % 3];
      links.push(3 * (j - parent - 1) + edge + 1);
      let k;
      if (!corner.has(v2)) {
        k = 0;
        name(v2, j);
        codes7.push(0);
      } else {
        const i2 = /** @type {number} */ (corner.get(v2));
        codes7.push(zigzag(i2 - i1) + 1);
        if (!escapeAll && lookup(i1, x, 1, i2)) k = 1;
        else if (!escapeAll && lookup(i0, x, 0, i2)) k = 2;
        else { k = 3; escapes.push(zigzag(i2 - i1)); }
      }
      tri = [i0, i1, /** @type {number} */ (corner.get(v2))];
      symbols.push(k); // the children are added below
    }
    // the open edges, as §9.13 says
    for (let e = 0; e < 3; e++) {
      const a = tri[e];
      const b = tri[(e + 1) % 3];
      let i = open.length - 1;
      while (i >= 0 && !(open[i][0] === b && open[i][1] === a)) i--;
      if (i >= 0) open.splice(i, 1);
      else open.push([a, b]);
    }
    order.push({ tri, parent, edge, src });
    // children: the free edges whose neighbours are not reached yet
    const free = parent < 0 ? [0, 1, 2] : [1, 2];
    /** @type {number[]} */
    let kids = [];
    for (const e of free) {
      const a = source[tri[e]];
      const b = source[tri[(e + 1) % 3]];
      const n = across.get(`${b},${a}`);
      if (oneChild && parent >= 0 && namer[tri[2]] === j && kids.length > 0) continue;
      if (n !== undefined && !reached[n] && !(drop && rnd() < 0.35)) { reached[n] = 1; kids.push(e); }
    }
    if (reverse) kids.reverse();
    if (parent < 0 && kids.length > 1 && rotate) kids = [...kids.slice(rotate % kids.length), ...kids.slice(0, rotate % kids.length)];
    const key = kids.join('');
    if (parent < 0) symbols.push(ROOT_LISTS.indexOf(key));
    else symbols[j] += 4 * ATTACHED_LISTS.indexOf(key);
    for (let q = kids.length - 1; q >= 0; q--) {
      const e = kids[q];
      const a = source[tri[e]];
      const b = source[tri[(e + 1) % 3]];
      stack.push({ src: /** @type {number} */ (across.get(`${b},${a}`)), parent: j, edge: e });
    }
  }
  const V = source.length;
  // faces, as §9.11: 0 the parent's (the previous triangle's for a root), 1 free, r + 2
  const face = order.map((o) => mesh.face[o.src]);
  const faces = order.map((o, j) => {
    const inherited = o.parent >= 0 ? face[o.parent] : j > 0 ? face[j - 1] : -1;
    return face[j] === inherited ? 0 : face[j] < 0 ? 1 : face[j] + 2;
  });
  const explicit = source.map((v) => mesh.coords[v] !== null);
  const flags = new Array(Math.ceil(V / 8)).fill(0);
  explicit.forEach((e, k) => { if (e) flags[k >> 3] |= 1 << (k & 7); });
  /** @type {number[]} */
  const picks = [];
  for (let k = 0; k < V; k++) {
    if (explicit[k]) continue;
    const planes = new Set();
    order.forEach((o, j) => { if (o.tri.includes(k) && face[j] >= 0) planes.add(face[j]); });
    if (planes.size > 3) picks.push(.../** @type {number[]} */ (mesh.picks?.get(source[k])));
  }
  /** @type {number[]} the explicit corners */
  const ex = [];
  for (let k = 0; k < V; k++) if (explicit[k]) ex.push(k);
  const E = ex.length;
  /**
   * The residuals of §9.11 (§9.12 with `gram`), of the coordinates or, with `tables`, the indices.
   * @param {boolean} gram @param {number[][] | null} tables
   */
  const residuals = (gram, tables) => {
    const value = (/** @type {number} */ k, /** @type {number} */ a) => {
      const c = /** @type {number[]} */ (mesh.coords[source[k]])[a];
      return tables ? tables[a].indexOf(c) : c;
    };
    /** @type {number[][]} */
    const out = [[], [], []];
    let previous = -1;
    for (const k of ex) {
      const t = namer[k];
      const o = t >= 0 ? order[t] : null;
      for (let a = 0; a < 3; a++) {
        let p;
        if (gram && o && explicit[o.tri[0]] && explicit[o.tri[1]] && explicit[order[o.parent].tri[(o.edge + 2) % 3]]) {
          p = value(o.tri[0], a) + value(o.tri[1], a) - value(order[o.parent].tri[(o.edge + 2) % 3], a);
        } else if (o && explicit[o.tri[0]]) p = value(o.tri[0], a);
        else p = previous >= 0 ? value(previous, a) : 0;
        out[a].push(zigzag(value(k, a) - p));
      }
      previous = k;
    }
    return out.flat();
  };
  /** @type {number[][] | null} */
  const tables = E > 0 && mode & 2 ? [0, 1, 2].map((a) => [...new Set(ex.map((k) => /** @type {number[]} */ (mesh.coords[source[k]])[a]))].sort((p, q) => p - q)) : null;
  const gridBytes = E > 0 ? grid.flatMap(f64) : [];
  const tableBytes = tables ? tables.flatMap((t) => [...varint(t.length), ...varint(zigzag(t[0])), ...varints(t.slice(1).map((v, i) => v - t[i] - 1))]) : [];
  // everything before the coordinates, which kinds 9 and 10 share (§9.14)
  const head = [...varints([V, T, escapes.length]), ...varints(symbols), ...varints(escapes), ...varints(faces), ...flags, ...varints(picks),
    ...(E > 0 ? [mode] : []), ...gridBytes, ...tableBytes];
  const kind9 = [...head, ...(E > 0 ? varints(residuals((mode & 1) !== 0, tables)) : [])];
  const tree = [...varints([V, T]), ...varints(links), ...varints(codes7), ...varints(faces), ...flags, ...varints(picks), ...gridBytes,
    ...(E > 0 ? varints(residuals((mode & 1) !== 0, null)) : [])];
  /** the value kind 10 resolves for corner k on axis a: its coordinate, or with tables its index */
  const value = (/** @type {number} */ k, /** @type {number} */ a) => {
    const c = /** @type {number[]} */ (mesh.coords[source[k]])[a];
    return BigInt(tables ? tables[a].indexOf(c) : c);
  };
  const walk = { tris: order.map((o) => o.tri), parent: order.map((o) => o.parent), edge: order.map((o) => o.edge), namer, explicit, ex, mode, tables };
  const multi = E > 0 ? residuals10(walk, value) : null;
  const kind10 = [...head, ...(multi ? varints(multi.residuals.map(zigzagBig)) : [])];
  return {
    kind9, kind10, head, walk, multi, tree, treeKind: mode & 1 ? 8 : 7, V, E, order, source, symbols, escapes, seconds,
    parts: { symbols, escapes, faces, flags, picks },
  };
}

// ---------------------------------------------------------------------------------------------
// Kind 10 (§9.14): the multi-parallelogram prediction, written for this test from §9.14's text in
// BigInt throughout (a plain Map of directed edges; nothing of the reader's sorted runs or its
// binary64 fast path)

/** ⌊x / n⌋, rounding toward −∞ @param {bigint} x @param {bigint} n */
const floorDiv = (x, n) => (x % n !== 0n && x < 0n ? x / n - 1n : x / n);
const LIMIT = 2n ** 52n;

/**
 * @typedef {object} Walk the decoded walk, as the encoder made it
 * @property {number[][]} tris corners of each triangle, in triangle order
 * @property {number[]} parent per triangle, -1 for a root
 * @property {number[]} edge per triangle, the parent's edge it is attached to
 * @property {number[]} namer per corner the triangle whose code 0 named it, -1 for a root's
 * @property {boolean[]} explicit per corner
 * @property {number[]} ex the explicit corners, ascending
 * @property {number} mode
 * @property {number[][] | null} tables
 */

/**
 * §9.14's parallelograms of every corner: per triangle in triangle order, per place s with i_s = k,
 * a = i_(s+1), b = i_(s+2), c the far corner of (a, b); kept where c exists and a, b, c are explicit
 * and below k; the first four.
 * @param {Walk} w @returns {number[][][]} per corner its list of [a, b, c]
 */
function multiGrams({ tris, explicit }) {
  /** @type {Map<string, number>} directed edge → the first triangle that has it */
  const first = new Map();
  tris.forEach((t, j) => {
    for (let e = 0; e < 3; e++) {
      const key = `${t[e]},${t[(e + 1) % 3]}`;
      if (!first.has(key)) first.set(key, j);
    }
  });
  /** @type {number[][][]} */
  const grams = explicit.map(() => []);
  for (const t of tris) {
    for (let s = 0; s < 3; s++) {
      const k = t[s];
      if (!explicit[k] || grams[k].length === 4) continue;
      const a = t[(s + 1) % 3];
      const b = t[(s + 2) % 3];
      const f = first.get(`${b},${a}`);
      if (f === undefined) continue;
      const c = /** @type {number} */ (tris[f].find((v) => v !== a && v !== b));
      if ([a, b, c].every((v) => explicit[v] && v < k)) grams[k].push([a, b, c]);
    }
  }
  return grams;
}

/**
 * The prediction of §9.14 for explicit corner k on axis ax from the values g resolved so far;
 * without parallelograms §9.13's (bit 0 of the mode: §9.12's, else §9.11's).
 * @param {Walk} w @param {number[][][]} grams @param {number} k @param {number} ax
 * @param {(k: number, a: number) => bigint} g @param {number} previous the previous explicit corner, -1 for none
 */
function predict10(w, grams, k, ax, g, previous) {
  const list = grams[k];
  if (list.length > 0) {
    let S = 0n;
    for (const [a, b, c] of list) S += g(a, ax) + g(b, ax) - g(c, ax);
    const n = BigInt(list.length);
    return floorDiv(S + n / 2n, n);
  }
  const t = w.namer[k];
  if (t >= 0) {
    const [i0, i1] = w.tris[t];
    const o = w.tris[w.parent[t]][(w.edge[t] + 2) % 3];
    if (w.mode & 1 && w.explicit[i0] && w.explicit[i1] && w.explicit[o]) return g(i0, ax) + g(i1, ax) - g(o, ax);
    if (w.explicit[i0]) return g(i0, ax);
  }
  return previous >= 0 ? g(previous, ax) : 0n;
}

/**
 * Kind 10's residuals (axis by axis, in corner order) of the values `value` gives, and what the
 * predictions met: how many corners had n parallelograms, and divisions that rounded a negative sum.
 * @param {Walk} w @param {(k: number, a: number) => bigint} value
 */
function residuals10(w, value) {
  const grams = multiGrams(w);
  /** @type {bigint[][]} */
  const out = [[], [], []];
  const histogram = [0, 0, 0, 0, 0];
  let negativeRounded = 0;
  let previous = -1;
  for (const k of w.ex) {
    histogram[grams[k].length]++;
    for (let a = 0; a < 3; a++) {
      const p = predict10(w, grams, k, a, value, previous);
      out[a].push(value(k, a) - p);
      const n = grams[k].length;
      if (n > 0) {
        let S = 0n;
        for (const [x, y, z] of grams[k]) S += value(x, a) + value(y, a) - value(z, a);
        if (S + BigInt(n >> 1) < 0n && (S + BigInt(n >> 1)) % BigInt(n) !== 0n) negativeRounded++;
      }
    }
    previous = k;
  }
  return { residuals: out.flat(), histogram, negativeRounded, grams };
}

/**
 * The reference decoding of kind 10 residuals (zigzag, axis by axis) over a walk, in BigInt: the
 * resolved values by corner, or the error a reader must give.
 * @param {Walk} w @param {bigint[]} zz
 * @returns {Map<number, bigint[]> | 'BAD_GROUP_STRUCTURE'}
 */
function decode10(w, zz) {
  const grams = multiGrams(w);
  const E = w.ex.length;
  /** @type {Map<number, bigint[]>} */
  const values = new Map();
  const g = (/** @type {number} */ k, /** @type {number} */ a) => /** @type {bigint[]} */ (values.get(k))[a];
  let previous = -1;
  for (let e = 0; e < E; e++) {
    const k = w.ex[e];
    values.set(k, [0n, 0n, 0n]);
    for (let a = 0; a < 3; a++) {
      const r = unzigzagBig(zz[a * E + e]);
      const v = predict10(w, grams, k, a, g, previous) + r;
      if (r > LIMIT || r < -LIMIT || v > LIMIT || v < -LIMIT) return 'BAD_GROUP_STRUCTURE';
      if (w.tables && (v < 0n || v >= BigInt(w.tables[a].length))) return 'BAD_GROUP_STRUCTURE';
      /** @type {bigint[]} */ (values.get(k))[a] = v;
    }
    previous = k;
  }
  return values;
}

// ---------------------------------------------------------------------------------------------
// Meshes

/** A torus of n × m quads, every corner explicit (integer coordinates), every triangle free. */
function torus(n = 8, m = 5) {
  /** @type {number[][]} */
  const tris = [];
  const id = (/** @type {number} */ i, /** @type {number} */ j) => ((i + n) % n) * m + ((j + m) % m);
  for (let i = 0; i < n; i++) {
    for (let j = 0; j < m; j++) {
      tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
    }
  }
  const coords = [];
  for (let i = 0; i < n; i++) {
    for (let j = 0; j < m; j++) {
      const a = (2 * Math.PI * i) / n;
      const b = (2 * Math.PI * j) / m;
      const r = 40 + 15 * Math.cos(b);
      coords.push([Math.round(r * Math.cos(a)), Math.round(r * Math.sin(a)), Math.round(15 * Math.sin(b))]);
    }
  }
  return { tris, face: tris.map(() => -1), coords };
}

/** The unit cube's planes as (ν, φ, h), local references 0-5: -z, +z, -y, +y, -x, +x. */
const CUBE_PLANES = [
  triplet([0, 0, -1], [0, 0, 0]), triplet([0, 0, 1], [0, 0, 1]), triplet([0, -1, 0], [0, 0, 0]),
  triplet([0, 1, 0], [0, 1, 0]), triplet([-1, 0, 0], [0, 0, 0]), triplet([1, 0, 0], [1, 0, 0]),
];

/** The unit cube (corner x + 2y + 4z): twelve triangles on their face planes, corners named or explicit. */
function cube(explicitCorners = /** @type {number[]} */ ([])) {
  const tris = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4], [2, 6, 7], [2, 7, 3], [0, 4, 6], [0, 6, 2], [1, 3, 7], [1, 7, 5]];
  const face = [0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5];
  const coords = [];
  for (let v = 0; v < 8; v++) coords.push(explicitCorners.includes(v) ? [v & 1, (v >> 1) & 1, v >> 2] : null);
  return { tris, face, coords };
}

/** A square pyramid (apex on four planes: picks), base 2 × 2 at z = 0, apex (1, 1, 1). */
function pyramid() {
  const planes = [
    triplet([0, 0, -1], [0, 0, 0]), triplet([0, -1, 1], [0, 0, 0]), triplet([1, 0, 1], [2, 0, 0]),
    triplet([0, 1, 1], [0, 2, 0]), triplet([-1, 0, 1], [0, 0, 0]),
  ];
  // base 0 (0,0,0), 1 (2,0,0), 2 (2,2,0), 3 (0,2,0); apex 4
  const tris = [[0, 2, 1], [0, 3, 2], [0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
  const face = [0, 0, 1, 2, 3, 4];
  return { planes, mesh: { tris, face, coords: [null, null, null, null, null], picks: new Map([[4, [0, 1, 3]]]) } };
}

/** Two tetrahedra apart and a lone triangle (three roots), explicit corners. */
function pieces() {
  const tet = (/** @type {number} */ o, /** @type {number} */ dx) => ({
    tris: [[o, o + 2, o + 1], [o, o + 1, o + 3], [o + 1, o + 2, o + 3], [o, o + 3, o + 2]],
    coords: [[dx, 0, 0], [dx + 4, 0, 0], [dx, 4, 0], [dx, 0, 4]],
  });
  const a = tet(0, 0);
  const b = tet(4, 10);
  const tris = [...a.tris, ...b.tris, [8, 9, 10]];
  return { tris, face: tris.map(() => -1), coords: [...a.coords, ...b.coords, [0, 0, 20], [3, 0, 20], [0, 3, 21]] };
}

/** A strip of a grid (open surface), explicit corners on few distinct values per axis. */
function grid(w = 6, h = 4) {
  const tris = [];
  const id = (/** @type {number} */ i, /** @type {number} */ j) => j * (w + 1) + i;
  for (let j = 0; j < h; j++) {
    for (let i = 0; i < w; i++) tris.push([id(i, j), id(i + 1, j), id(i + 1, j + 1)], [id(i, j), id(i + 1, j + 1), id(i, j + 1)]);
  }
  const coords = [];
  for (let j = 0; j <= h; j++) for (let i = 0; i <= w; i++) coords.push([1000 * i, -7 * j * j, (i + j) % 2]);
  return { tris, face: tris.map(() => -1), coords };
}

/** The decoded group's triangles in source vertices, and its explicit corners' coordinates by source vertex. */
function decoded(/** @type {Uint8Array} */ bytes, /** @type {{source: number[]}} */ enc) {
  const f = readNode(bytes);
  const shell = conformanceJson(f).groups[0].shell;
  /** @type {number[][]} */
  const tris = shell.facets.map((/** @type {number[]} */ t) => [enc.source[t[1]], enc.source[t[2]], enc.source[t[3]]]);
  return { f, shell, tris };
}

/**
 * Encodes `mesh` as kind 9 with `options`, decodes it, and checks: the triangles are the mesh's (in
 * walk order, each as its source triangle turned), the explicit corners at origin + step × their
 * coordinates, and the report and geometry equal to those of the same triangles as a shell tree.
 * @param {number[][]} planes @param {Mesh} mesh @param {Parameters<typeof encode>[1]} options
 * @param {9 | 10} [kind] 10: the same walk with §9.14's prediction, in a 4.2 file
 */
function roundTrip(planes, mesh, options = {}, kind = 9) {
  const enc = encode(mesh, options);
  const bytes = file({ planes, groups: [{ kind, data: kind === 10 ? enc.kind10 : enc.kind9 }], version: [4, kind === 10 ? 2 : 1] });
  const { f, shell, tris } = decoded(bytes, enc);
  assert.equal(tris.length, mesh.tris.length);
  tris.forEach((t, j) => {
    const s = mesh.tris[enc.order[j].src];
    const r = s.indexOf(t[0]);
    assert.deepEqual([s[r], s[(r + 1) % 3], s[(r + 2) % 3]], t, `triangle ${j}`);
  });
  const [ox, oy, oz, step] = options.grid ?? [0.5, -1, 2, 0.25];
  const pos = /** @type {any} */ (f.meshes[0]).positions64;
  enc.source.forEach((v, k) => {
    const c = mesh.coords[v];
    if (c) assert.deepEqual([pos[3 * k], pos[3 * k + 1], pos[3 * k + 2]], [ox + step * c[0], oy + step * c[1], oz + step * c[2]], `corner ${k}`);
  });
  // the same triangles as a shell tree: the same report, kind apart, and the same geometry
  const tree = conformanceJson(readNode(file({ planes, groups: [{ kind: enc.treeKind, data: enc.tree }], version: [3, enc.treeKind - 4] })));
  const walk = conformanceJson(f);
  assert.deepEqual(walk.groups[0].shell, tree.groups[0].shell);
  assert.deepEqual(walk.geometry, tree.geometry);
  assert.equal(walk.groups[0].kind, kind);
  assert.deepEqual(walk.header.version, [4, kind === 10 ? 2 : 1]);
  assert.deepEqual(walk.findings, []);
  // and the browser entry reads it alike
  assert.deepEqual(conformanceJson(readBrowser(bytes)), walk);
  return { enc, shell, f };
}

const ONE_PLANE = [triplet([0, 0, 1], [0, 0, 0])];

test('§9.13: a closed torus walked depth first: third corners named before are left or right', () => {
  let seconds = 0;
  for (const mode of [0, 1, 2, 3]) {
    for (const reverse of [false, true]) {
      for (const oneChild of [false, true]) {
        const { enc } = roundTrip(ONE_PLANE, torus(20, 12), { mode, reverse, oneChild });
        // both left and right appear, and some triangles have two children
        assert.ok(enc.symbols.some((s) => s % 4 === 1) && enc.symbols.some((s) => s % 4 === 2));
        assert.ok(enc.symbols.slice(1).some((s) => s >= 12));
        seconds += enc.seconds;
      }
    }
  }
  // left or right past the newest edge (whose other end was the parent's opposite corner)
  assert.ok(seconds > 0);
  // a walk of one child after each new corner: left or right for all but a few (where the walk
  // closes the torus's loops), as §9.13 says of a manifold walked depth first
  const big = encode(torus(60, 100), { oneChild: true });
  const codes = [0, 0, 0, 0];
  big.symbols.slice(1).forEach((s) => codes[s % 4]++);
  assert.ok(codes[3] < 0.01 * big.symbols.length && codes[1] + codes[2] > 0.49 * big.symbols.length, `${codes}`);
});

test('§9.13: the same triangles coded with escapes only (code 3 + escape) decode alike', () => {
  const a = roundTrip(ONE_PLANE, torus(), { escapeAll: true });
  const b = roundTrip(ONE_PLANE, torus(), {});
  assert.deepEqual(a.shell, b.shell);
  assert.ok(a.enc.escapes.length > 3);
});

test('§9.13: every root list (symbols 0-15) and attached list (0-4), several roots, an open grid', () => {
  const seen = new Set();
  let seconds = 0;
  for (let rotate = 0; rotate < 3; rotate++) {
    for (const reverse of [false, true]) {
      for (const [planes, mesh, drop] of /** @type {[number[][], Mesh, number][]} */ ([[ONE_PLANE, pieces(), 0], [ONE_PLANE, grid(), 0], [CUBE_PLANES, cube(), 0],
        ...[1, 7, 11, 19].map((seed) => /** @type {[number[][], Mesh, number]} */ ([ONE_PLANE, torus(), seed + rotate])),
        [ONE_PLANE, grid(), 3 + rotate], [CUBE_PLANES, cube(), 5 + rotate], [ONE_PLANE, pieces(), 13 + rotate]])) {
        const { enc } = roundTrip(planes, mesh, { rotate, reverse, mode: 3, drop });
        seconds += enc.seconds;
        let top = 0;
        enc.symbols.forEach((s) => {
          seen.add(top === 0 ? `r${s}` : `a${s >> 2}`);
          top += top === 0 ? ROOT_LISTS[s].length : ATTACHED_LISTS[s >> 2].length - 1;
        });
      }
    }
  }
  for (let s = 0; s < 16; s++) assert.ok(seen.has(`r${s}`), `root list ${s}: ${[...seen].sort()}`);
  for (let c = 0; c < 5; c++) assert.ok(seen.has(`a${c}`), `attached list ${c}`);
  assert.ok(seconds > 0);
});

test('§9.13: named corners from the faces (the cube), picks (a pyramid\'s apex), mixed with explicit ones', () => {
  const { shell } = roundTrip(CUBE_PLANES, cube());
  assert.deepEqual(shell.explicit, []);
  assert.equal(shell.vertex_planes.length, 8);
  for (const mode of [0, 1, 2, 3]) roundTrip(CUBE_PLANES, cube([0, 3, 5, 6, 7]), { mode });
  const { planes, mesh } = pyramid();
  const p = roundTrip(planes, mesh);
  const f = p.f;
  const pos = /** @type {any} */ (f.meshes[0]).positions64;
  const apex = p.enc.source.indexOf(4);
  assert.ok(Math.hypot(pos[3 * apex] - 1, pos[3 * apex + 1] - 1, pos[3 * apex + 2] - 1) < 1e-12);
  // the cube decodes closed: volume 1 (kind 9 reports no volume, like every shell, so from the mesh)
  const c = readNode(file({ planes: CUBE_PLANES, groups: [{ kind: 9, data: encode(cube()).kind9 }] })).mesh();
  let vol = 0;
  for (let t = 0; t < c.indices.length; t += 3) {
    const [a, b, d] = [0, 1, 2].map((s) => [0, 1, 2].map((r) => c.positions64[3 * c.indices[t + s] + r]));
    vol += (a[0] * (b[1] * d[2] - b[2] * d[1]) - a[1] * (b[0] * d[2] - b[2] * d[0]) + a[2] * (b[0] * d[1] - b[1] * d[0])) / 6;
  }
  assert.ok(Math.abs(vol - 1) < 1e-12, `${vol}`);
});

test('§9.13: tables: indices into each axis\'s values, predicted and resolved as coordinates are', () => {
  const mesh = grid(9, 5);
  const plain = roundTrip(ONE_PLANE, mesh, { mode: 0 });
  const tables = roundTrip(ONE_PLANE, mesh, { mode: 2 });
  const both = roundTrip(ONE_PLANE, mesh, { mode: 3 });
  assert.deepEqual(tables.shell, plain.shell);
  assert.deepEqual(both.shell, plain.shell);
  // (the grid's x takes 10 values, y 6, z 2: short tables, the coordinates indices)
  // compressed payloads of kind 9 too
  const bytes = file({ planes: ONE_PLANE, groups: [{ kind: 9, data: both.enc.kind9, method: 2 }, { kind: 9, data: both.enc.kind9, method: 1 }] });
  const two = conformanceJson(readNode(bytes));
  assert.deepEqual(two.groups[0].shell, plain.shell);
  assert.deepEqual(two.groups[1].shell, plain.shell);
});

test('§9.13: the faces: the parent\'s, free, a reference; the previous triangle\'s for a later root', () => {
  const mesh = pieces();
  mesh.face = mesh.tris.map((_, j) => (j < 4 ? 0 : j < 8 ? -1 : 1));
  const planes = [triplet([0, 0, 1], [0, 0, 0]), triplet([0, 1, 0], [0, 0, 0])];
  const { enc, shell } = roundTrip(planes, mesh);
  assert.deepEqual(shell.facets.map((/** @type {number[]} */ t) => t[0]), enc.order.map((o) => mesh.face[o.src]));
  // faces 0 throughout: the first root free, every later one the previous triangle's: all free
  const tail = enc.kind9.slice(enc.kind9.length - 1 - 32 - 3 * enc.E); // mode, grid, coordinates
  const data = file({ planes, groups: [{ kind: 9, data: body({ V: enc.V, T: mesh.tris.length, symbols: enc.symbols, escapes: enc.escapes, faces: new Array(mesh.tris.length).fill(0), flags: enc.parts.flags, tail }) }] });
  assert.ok(conformanceJson(readNode(data)).groups[0].shell.facets.every((/** @type {number[]} */ t) => t[0] === -1));
});

// ---------------------------------------------------------------------------------------------
// Hand-built bodies: the rules of the walk, and every error of §9.13

/**
 * Kind 9 data from its fields. Without explicit corners (flags all 0) nothing follows the picks.
 * @param {{V: number, T: number, X?: number, symbols: number[], escapes?: (number | bigint)[], faces?: number[], flags: number[], picks?: number[], tail?: number[]}} d
 */
function body({ V, T, X, symbols, escapes = [], faces, flags, picks = [], tail = [] }) {
  return [...varints([V, T, X ?? escapes.length]), ...varints(symbols), ...varints(escapes), ...varints(faces ?? new Array(T).fill(1)), ...flags, ...varints(picks), ...tail];
}

/** A body whose corners are all explicit at 0, 0, 0 ... apart: mode, grid, coordinates follow. */
function explicitBody(/** @type {Parameters<typeof body>[0]} */ d, mode = 0, tables = /** @type {number[]} */ ([]), residuals = /** @type {(number | bigint)[] | null} */ (null)) {
  const V = d.V;
  const flags = new Array(Math.ceil(V / 8)).fill(0);
  for (let k = 0; k < V; k++) flags[k >> 3] |= 1 << (k & 7);
  return body({ ...d, flags, tail: [mode, ...[0, 0, 0, 1].flatMap(f64), ...tables, ...varints(residuals ?? new Array(3 * V).fill(2))] });
}

/** @param {number[]} data @param {[number, number]} [version] */
const kind9 = (data, version = [4, 1]) => file({ planes: ONE_PLANE, groups: [{ kind: 9, data }], version });

/** The triangles of a walk over all-explicit corners. @param {Parameters<typeof body>[0]} d */
function trianglesOf(d) {
  return conformanceJson(readNode(kind9(explicitBody(d)))).groups[0].shell.facets.map((/** @type {number[]} */ t) => t.slice(1));
}

test('§9.13 walk: slots pushed in reverse (the first child next), edges across (i0 = q(e+1), i1 = q(e))', () => {
  // root (0 1 2) with children across edges 2 then 0 (list 8); the child across edge 2 first:
  // (q0, q2) = (0, 2), a new corner 3; then across edge 0: (q1, q0) = (1, 0), new corner 4
  assert.deepEqual(trianglesOf({ V: 5, T: 3, symbols: [8, 0, 0], escapes: [0, 0, 0], flags: [] }), [[0, 1, 2], [0, 2, 3], [1, 0, 4]]);
  // the same with list 5 (0, 2): edge 0 first
  assert.deepEqual(trianglesOf({ V: 5, T: 3, symbols: [5, 0, 0], escapes: [0, 0, 0], flags: [] }), [[0, 1, 2], [1, 0, 3], [0, 2, 4]]);
  // an attached triangle's list 4 (2, 1), symbol 16: (i0 i1 i2) = (1 0 3); its edge 2 (3 -> 1)
  // first: (1 3 4); then its edge 1 (0 -> 3): (3 0 5)
  assert.deepEqual(trianglesOf({ V: 6, T: 4, symbols: [1, 16, 0, 0], escapes: [0, 0, 0], flags: [] }), [[0, 1, 2], [1, 0, 3], [1, 3, 4], [3, 0, 5]]);
  // depth first: a child's subtree (list 1 of (1 0 3): its edge 1, 0 -> 3) before the root's next child
  assert.deepEqual(trianglesOf({ V: 6, T: 4, symbols: [5, 4, 0, 0], escapes: [0, 0, 0], flags: [] }), [[0, 1, 2], [1, 0, 3], [3, 0, 4], [0, 2, 5]]);
  // a second root once the stack is empty; its codes step back from n (1 the newest corner)
  assert.deepEqual(trianglesOf({ V: 4, T: 2, symbols: [0, 0], escapes: [0, 0, 0, 1, 0, 4], flags: [] }), [[0, 1, 2], [2, 3, 0]]);
  // code 3 + escape: corner i1 + z(escape)
  assert.deepEqual(trianglesOf({ V: 4, T: 3, symbols: [3, 4, 3], escapes: [0, 0, 0, 1], flags: [] }), [[0, 1, 2], [0, 2, 3], [3, 2, 1]]);
});

test('§9.13 walk: left and right take the newest open edge at i1 / i0, skipping one whose other end is x', () => {
  // a fan around corner 0: root (0 1 2) [list (2)], then across each new triangle's edge 2
  // (i2 -> 0): (0 2 3), (0 3 4), and last (0 4 i2) with x = 3. Right: the newest open edge starting
  // at i0 = 0 is (0, 1): i2 = 1, closing the fan. Left: the newest ending at i1 = 4 is (3, 4), whose
  // start is x; there is no second: refused
  const fan = (/** @type {number} */ code) => ({ V: 5, T: 4, symbols: [3, 8, 8, code], escapes: [0, 0, 0], flags: [] });
  assert.deepEqual(trianglesOf(fan(2)), [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 1]]);
  assert.equal(outcome(kind9(explicitBody(fan(1)))), 'BAD_GROUP_STRUCTURE');
  // root (0 1 2) [list (1)], its child across edge 1 (2 1 i2), x = 0: the only open edge ending at
  // 1 is (0, 1), the only one starting at 2 is (2, 0): both at x, so left and right name nothing
  assert.equal(outcome(kind9(explicitBody({ V: 4, T: 2, symbols: [2, 1], escapes: [0, 0, 0], flags: [] }))), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(kind9(explicitBody({ V: 4, T: 2, symbols: [2, 2], escapes: [0, 0, 0], flags: [] }))), 'BAD_GROUP_STRUCTURE');
  // root (0 1 2) [list (2, 1)]: (0 2 3) a leaf, then (2 1 i2), x = 0: open (0,1) (1,2) (2,3) (3,0).
  // Right at i0 = 2: (2, 3): i2 = 3. Left at i1 = 1: (0, 1) at x, no second: refused
  assert.deepEqual(trianglesOf({ V: 4, T: 3, symbols: [9, 0, 2], escapes: [0, 0, 0], flags: [] }), [[0, 1, 2], [0, 2, 3], [2, 1, 3]]);
  assert.equal(outcome(kind9(explicitBody({ V: 4, T: 3, symbols: [9, 0, 1], escapes: [0, 0, 0], flags: [] }))), 'BAD_GROUP_STRUCTURE');
  // a non-manifold chain: root (0 1 2) [list (0)]; (1 0 3) [list (1)]; across its edge 1 (0 -> 3)
  // (3 0 i2), i2 = corner 1 by escape (i1 + z(2) = 0 + 1): its edges (3, 0) closes (0, 3), (0, 1)
  // enters (the root's was closed by (1 0 3)), (1, 3) closes (3, 1). Open: (1,2) (2,0) (0,1).
  // [list (1)]: across its edge 1 (0 -> 1): (1 0 i2), x = 3. Left at i1 = 0: the newest ending at
  // 0 is (2, 0): i2 = 2. Right at i0 = 1: the newest starting at 1 is (0, 1)? No: (1, 2): i2 = 2
  const chain = (/** @type {number} */ code) => ({ V: 4, T: 4, symbols: [1, 4, 4 + 3, code], escapes: [0, 0, 0, 2], flags: [] });
  assert.deepEqual(trianglesOf(chain(1)), [[0, 1, 2], [1, 0, 3], [3, 0, 1], [1, 0, 2]]);
  assert.deepEqual(trianglesOf(chain(2)), [[0, 1, 2], [1, 0, 3], [3, 0, 1], [1, 0, 2]]);
});

test('OpenEdges: newest entries, stacks of one edge, closing the newest reverse; against a plain list', () => {
  /** A deterministic generator. @param {number} seed */
  const random = (seed) => () => {
    seed = (seed + 0x6d2b79f5) | 0;
    let t = Math.imul(seed ^ (seed >>> 15), 1 | seed);
    t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  for (const corners of [3, 5, 40]) {
    const rnd = random(corners);
    const fast = new OpenEdges(corners, 30000);
    /** @type {number[][]} */
    const list = [];
    const pairs = new Set();
    for (let i = 0; i < 10000; i++) {
      const a = Math.floor(rnd() * corners);
      let b = Math.floor(rnd() * corners);
      if (b === a) b = (a + 1) % corners;
      fast.edge(a, b);
      pairs.add(`${Math.min(a, b)},${Math.max(a, b)}`);
      let r = list.length - 1;
      while (r >= 0 && !(list[r][0] === b && list[r][1] === a)) r--;
      if (r >= 0) list.splice(r, 1);
      else list.push([a, b]);
      const c = Math.floor(rnd() * corners);
      const not = Math.floor(rnd() * corners);
      for (const at of /** @type {const} */ ([0, 1])) {
        let want = -1;
        let skipped = false;
        for (let q = list.length - 1; q >= 0; q--) {
          if (list[q][1 - at] !== c) continue;
          if (!skipped && list[q][at] === not) { skipped = true; continue; }
          want = list[q][at];
          break;
        }
        assert.equal(at === 0 ? fast.left(c, not) : fast.right(c, not), want, `step ${i}`);
      }
    }
    // one slot per undirected edge ever entered, both directions' stacks in it
    assert.equal(fast.keys, pairs.size);
  }
});

test('§9.13 errors: the counts (BAD_GROUP_STRUCTURE), read first (BAD_PAYLOAD)', () => {
  const ok = { V: 3, T: 1, symbols: [0], escapes: [0, 0, 0], flags: [] };
  assert.equal(outcome(kind9(explicitBody(ok))), 'ok');
  assert.equal(outcome(kind9([3, 1])), 'BAD_PAYLOAD');
  assert.equal(outcome(kind9([3, 1, 0x80])), 'BAD_PAYLOAD');
  assert.equal(outcome(kind9(body({ ...ok, V: 2 }))), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(kind9(body({ ...ok, T: 0, symbols: [] }))), 'BAD_GROUP_STRUCTURE');
  // T at most half the bytes left after the three counts; X at most those bytes; V at most 8 ×
  assert.equal(outcome(kind9([3, 3, 0, 0, 0])), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(kind9([3, 1, 9, 0, 0, 0, 0, 0, 0, 0, 0])), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(kind9([3, 1, 8, 0, 0, 0, 0, 0, 0, 0, 0])), 'BAD_PAYLOAD'); // X = 8 fits, 8 escapes do not
  assert.equal(outcome(kind9([17, 1, 0, 0])), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(kind9([16, 1, 0, 0, 1])), 'BAD_PAYLOAD'); // V = 16 fits 8 × 2: the body ends inside the flags
});

test('§9.13 errors: a body ending inside the symbols, escapes, faces, flags is BAD_PAYLOAD, whatever else is wrong', () => {
  // a symbol out of range and the body short of the faces
  assert.equal(outcome(kind9([3, 1, 3, 99, 0, 0, 0])), 'BAD_PAYLOAD');
  assert.equal(outcome(kind9([3, 1, 3, 0, 0, 0, 0, 1])), 'BAD_PAYLOAD'); // no flag byte
  assert.equal(outcome(kind9([3, 1, 3, 0, 0, 0, 0, 1, 0xf8])), 'BAD_PAYLOAD'); // a set padding bit
  assert.equal(outcome(kind9([3, 1, 3, 99, 0, 0, 0, 1, 0xf8])), 'BAD_PAYLOAD'); // and a bad symbol
  assert.equal(outcome(kind9([3, 1, 3, 99, 0, 0, 0, 1, 0])), 'BAD_GROUP_STRUCTURE');
});

test('§9.13 errors: the walk (symbols, stack, escapes, corners), all BAD_GROUP_STRUCTURE', () => {
  const show = (/** @type {any} */ d) => JSON.stringify(d, (_, v) => (typeof v === 'bigint' ? `${v}` : v));
  const bgs = (/** @type {Parameters<typeof body>[0]} */ d) => assert.equal(outcome(kind9(explicitBody(d))), 'BAD_GROUP_STRUCTURE', show(d));
  const good = (/** @type {Parameters<typeof body>[0]} */ d) => assert.equal(outcome(kind9(explicitBody(d))), 'ok', show(d));
  good({ V: 4, T: 2, symbols: [1, 0], escapes: [0, 0, 0], flags: [] });
  bgs({ V: 3, T: 1, symbols: [16], escapes: [0, 0, 0], flags: [] }); // a root's symbol past 15
  bgs({ V: 4, T: 2, symbols: [1, 16], escapes: [0, 0, 0], flags: [] }); // list 4 = (2, 1) leaves 2 slots
  bgs({ V: 4, T: 2, symbols: [1, 20], escapes: [0, 0, 0], flags: [] }); // an attached symbol past 19
  bgs({ V: 4, T: 2, symbols: [1, 2 ** 60], escapes: [0, 0, 0], flags: [] });
  bgs({ V: 4, T: 2, symbols: [2, 0], escapes: [0, 0, 0, 5], flags: [] }); // escapes left over
  bgs({ V: 4, T: 1, symbols: [1], escapes: [0, 0, 0], flags: [] }); // a slot left on the stack
  bgs({ V: 3, T: 1, symbols: [0], escapes: [0, 0], flags: [] }); // a root with two escapes
  bgs({ V: 4, T: 2, symbols: [1, 3], escapes: [0, 0, 0], flags: [] }); // code 3 with no escape left
  good({ V: 4, T: 3, symbols: [3, 4, 3], escapes: [0, 0, 0, 1], flags: [] }); // 3 + z(1) = i1 - 1
  bgs({ V: 3, T: 1, symbols: [0], escapes: [0, 0, 3], flags: [] }); // a root's code naming corner -1
  bgs({ V: 3, T: 1, symbols: [0], escapes: [0, 1, 0], flags: [] }); // (0 0 1): one corner twice
  bgs({ V: 4, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 0], flags: [] }); // i2 = i1: one corner twice
  // (1 0 i2): i2 = i1 + z(escape)
  bgs({ V: 3, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 2], flags: [] }); // 0 + 1 = i0: one corner twice
  good({ V: 3, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 4], flags: [] }); // 0 + 2: (1 0 2)
  bgs({ V: 3, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 6], flags: [] }); // 0 + 3: not named before
  bgs({ V: 3, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 5], flags: [] }); // 0 - 3: below 0
  bgs({ V: 3, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 1], flags: [] }); // 0 - 1: below 0
  bgs({ V: 3, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 2 ** 60], flags: [] });
  bgs({ V: 3, T: 2, symbols: [1, 3], escapes: [0, 0, 0, 2n ** 64n - 1n], flags: [] });
  bgs({ V: 5, T: 2, symbols: [1, 0], escapes: [0, 0, 0], flags: [] }); // final n 4, V 5
  bgs({ V: 4, T: 2, symbols: [0, 0], escapes: [0, 0, 0, 0, 0, 0], flags: [] }); // n reaches 6 > V
  bgs({ V: 3, T: 2, symbols: [1, 0], escapes: [0, 0, 0], flags: [] }); // the attached new corner past V
  good({ V: 3, T: 2, symbols: [0, 0], escapes: [0, 0, 0, 2, 1, 3], flags: [] }); // a second root over old corners
});

test('§9.13 errors: the faces, named corners and picks, as §9.11', () => {
  // one named corner on the face planes; two planes, the second bounding
  const planes = [triplet([0, 0, 1], [0, 0, 0]), triplet([0, 1, 0], [0, 0, 0])];
  const g = (/** @type {number[]} */ data, bounding = [1]) => file({ planes, groups: [{ kind: 9, data, bounding }] });
  const walk = { V: 3, T: 1, symbols: [0], escapes: [0, 0, 0] };
  const ex = [...[0, 0, 0, 1].flatMap(f64), ...new Array(9).fill(0)];
  assert.equal(outcome(g(body({ ...walk, faces: [2], flags: [7], tail: [0, ...ex] }))), 'ok');
  assert.equal(outcome(g(body({ ...walk, faces: [3], flags: [7], tail: [0, ...ex] }))), 'BAD_GROUP_STRUCTURE'); // a bounding plane
  assert.equal(outcome(g(body({ ...walk, faces: [4], flags: [7], tail: [0, ...ex] }))), 'BAD_GROUP_STRUCTURE'); // above m + 1
  // the face error comes before the picks are read: a body ending there is still BAD_GROUP_STRUCTURE
  assert.equal(outcome(g(body({ ...walk, faces: [4], flags: [7] }))), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(g(body({ ...walk, faces: [2], flags: [7] }))), 'BAD_PAYLOAD');
  // a named corner on one face plane: BAD_GROUP_STRUCTURE (after the rest is read, note 2)
  assert.equal(outcome(g(body({ ...walk, faces: [2], flags: [6], tail: [0, ...[0, 0, 0, 1].flatMap(f64), 0, 0, 0, 0, 0, 0] }))), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(g(body({ ...walk, faces: [2], flags: [6], tail: [0, ...[0, 0, 0, 1].flatMap(f64), 0, 0, 0, 0, 0] }))), 'BAD_PAYLOAD');
  // the pyramid's picks: not ascending, past |P|, cut short
  const { planes: pp, mesh } = pyramid();
  const enc = encode(mesh);
  const withPicks = (/** @type {number[]} */ picks) => file({ planes: pp, groups: [{ kind: 9, data: body({ V: enc.V, T: 6, symbols: enc.symbols, escapes: enc.escapes, faces: enc.parts.faces, flags: enc.parts.flags, picks }) }] });
  assert.equal(outcome(withPicks([0, 1, 3])), 'ok');
  assert.equal(outcome(withPicks([0, 1, 2])), 'ok');
  assert.equal(outcome(withPicks([1, 0, 3])), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(withPicks([0, 1, 4])), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(withPicks([0, 1])), 'BAD_PAYLOAD');
  assert.equal(outcome(withPicks([0, 1, 3, 0])), 'BAD_GROUP_STRUCTURE'); // a byte after the picks (no explicit corner)
});

test('§9.13 errors: the mode, the grid, the tables, the coordinates', () => {
  const walk = { V: 3, T: 1, symbols: [0], escapes: [0, 0, 0], flags: [] };
  const go = (/** @type {number} */ mode, /** @type {number[]} */ tables = [], /** @type {(number | bigint)[] | null} */ res = null) => outcome(kind9(explicitBody(walk, mode, tables, res)));
  assert.equal(go(0), 'ok');
  assert.equal(go(1), 'ok');
  for (const mode of [4, 5, 8, 0x80, 0xfd]) assert.equal(go(mode), 'BAD_GROUP_STRUCTURE', `mode ${mode}`);
  // bit 1 decides whether tables follow whatever the bits above it hold: here none follow
  assert.equal(go(0xff), 'BAD_PAYLOAD');
  // a mode with a bit above 1 is checked with the rest: a body ending inside the coordinates first
  assert.equal(outcome(kind9(body({ ...walk, flags: [7], tail: [4, ...[0, 0, 0, 1].flatMap(f64), 2, 2, 2] }))), 'BAD_PAYLOAD');
  // grid
  const grid = (/** @type {number[]} */ g) => outcome(kind9(body({ ...walk, flags: [7], tail: [0, ...g.flatMap(f64), ...new Array(9).fill(0)] })));
  assert.equal(grid([0, 0, 0, 1]), 'ok');
  assert.equal(grid([0, NaN, 0, 1]), 'BAD_GROUP_STRUCTURE');
  assert.equal(grid([0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  assert.equal(grid([0, 0, 0, -1]), 'BAD_GROUP_STRUCTURE');
  assert.equal(grid([0, 0, 0, Infinity]), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(kind9(body({ ...walk, flags: [7], tail: [0, ...new Array(31).fill(0)] }))), 'BAD_PAYLOAD');
  assert.equal(outcome(kind9(body({ ...walk, flags: [7] }))), 'BAD_PAYLOAD'); // no mode
  // tables: per axis a count 1..E, the first value, the gaps; coordinates then indices
  const t = (/** @type {(number | bigint)[][]} */ axes) => axes.flatMap((a) => varints(a));
  const Z = 2 ** 52;
  // three corners: x indices 0, 1, 2 (residuals +1, +1 from the previous explicit corner), y and z 0
  const res = [0, 2, 2, 0, 0, 0, 0, 0, 0];
  const zeros = new Array(9).fill(0);
  const f = readNode(kind9(explicitBody(walk, 2, t([[3, zigzag(-5), 0, 9], [1, zigzag(4)], [1, zigzag(-Z)]]), res)));
  assert.deepEqual(conformanceJson(f).groups[0].shell.grid, [[-5, 4, -Z], [-4, 4, -Z], [6, 4, -Z]]);
  assert.equal(go(2, t([[3, 0, 0, 0], [1, 0], [1, 0]]), res), 'ok');
  assert.equal(go(2, t([[0], [1, 0], [1, 0]]), res), 'BAD_GROUP_STRUCTURE'); // a count of 0
  assert.equal(go(2, t([[4, 0, 0, 0, 0], [1, 0], [1, 0]]), res), 'BAD_GROUP_STRUCTURE'); // above E
  assert.equal(go(2, t([[3, 0, 0, 0], [1, 0], [4, 0, 0, 0, 0]]), res), 'BAD_GROUP_STRUCTURE');
  // a count is checked as it is read: before a body that ends inside its values
  const cut = (/** @type {number[]} */ tables) => outcome(kind9(body({ ...walk, flags: [7], tail: [2, ...[0, 0, 0, 1].flatMap(f64), ...tables] })));
  assert.equal(cut([4, 0]), 'BAD_GROUP_STRUCTURE');
  assert.equal(cut([0]), 'BAD_GROUP_STRUCTURE');
  assert.equal(cut([3, 0]), 'BAD_PAYLOAD');
  assert.equal(cut([]), 'BAD_PAYLOAD');
  // an index outside its table (x resolves to 3 in a table of 3; y to -1)
  assert.equal(go(2, t([[3, 0, 0, 0], [1, 0], [1, 0]]), [0, 2, 4, 0, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  assert.equal(go(2, t([[3, 0, 0, 0], [1, 0], [1, 0]]), [0, 2, 2, 1, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  // table values beyond 2^52: the first, and a gap past it (exactly at the bound is allowed)
  assert.equal(go(2, t([[1, zigzag(Z)], [1, 0], [1, zigzag(-Z)]]), zeros), 'ok');
  assert.equal(go(2, t([[1, zigzag(Z) + 2], [1, 0], [1, 0]]), zeros), 'BAD_GROUP_STRUCTURE'); // 2^52 + 1
  assert.equal(go(2, t([[1, 2n ** 53n + 1n], [1, 0], [1, 0]]), zeros), 'BAD_GROUP_STRUCTURE'); // -2^52 - 1
  assert.equal(go(2, t([[1, 2n ** 64n - 1n], [1, 0], [1, 0]]), zeros), 'BAD_GROUP_STRUCTURE');
  assert.equal(go(2, t([[2, zigzag(-Z), 2 ** 53 - 1], [1, 0], [1, 0]]), [0, 2, 0, 0, 0, 0, 0, 0, 0]), 'ok');
  assert.equal(go(2, t([[2, zigzag(-Z), 2 ** 53], [1, 0], [1, 0]]), [0, 2, 0, 0, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  assert.equal(go(2, t([[2, zigzag(-Z), 2n ** 53n + 1n], [1, 0], [1, 0]]), [0, 2, 0, 0, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  assert.equal(go(2, t([[2, zigzag(Z - 1), 0], [1, 0], [1, 0]]), [0, 2, 0, 0, 0, 0, 0, 0, 0]), 'ok');
  assert.equal(go(2, t([[2, zigzag(Z - 1), 1], [1, 0], [1, 0]]), [0, 2, 0, 0, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  // a table value is a value: checked with the rest, after the coordinates are read
  assert.equal(outcome(kind9(body({ ...walk, flags: [7], tail: [2, ...[0, 0, 0, 1].flatMap(f64), ...t([[1, zigzag(Z) + 2], [1, 0], [1, 0]]), 0, 0] }))), 'BAD_PAYLOAD');
  // residuals and coordinates beyond 2^52, without tables
  assert.equal(go(0, [], [zigzag(Z), 0, 0, 0, 0, 0, 0, 0, 0]), 'ok');
  assert.equal(go(0, [], [zigzag(Z) + 2, 0, 0, 0, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  assert.equal(go(0, [], [zigzag(Z), 2, 0, 0, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE'); // 2^52 + 1
  // a residual beyond 2^52 with tables
  assert.equal(go(2, t([[1, 0], [1, 0], [1, 0]]), [zigzag(Z) + 2, 0, 0, 0, 0, 0, 0, 0, 0]), 'BAD_GROUP_STRUCTURE');
  // bytes after the coordinates
  assert.equal(outcome(kind9([...explicitBody(walk), 0])), 'BAD_GROUP_STRUCTURE');
  assert.equal(outcome(kind9(explicitBody(walk).slice(0, -1))), 'BAD_PAYLOAD');
});

test('§9.12 in a walk: the parallelogram bit predicts i0 + i1 - o, of indices with tables', () => {
  // root (0 1 2) at (0,0,0) (4,0,0) (0,4,0); its child across edge 0 (1 -> 0): (1 0 3), o = 2:
  // predicted (4,0,0) + (0,0,0) - (0,4,0) = (4,-4,0); residual (1, 1, 1) puts 3 at (5,-3,1)
  const walk = { V: 4, T: 2, symbols: [1, 0], escapes: [0, 0, 0], flags: [] };
  // residuals (zigzag) by axis, corners 0-3; a root's corners predict from the previous explicit corner
  const xs = [0, 8, 7, 2]; // 0, +4, -4, then +1 over the parallelogram (or over corner 1 without it)
  const ys = [0, 0, 8, 2]; // 0, 0, +4, +1
  const zs = [0, 0, 0, 2]; // 0, 0, 0, +1
  const grid = (/** @type {number} */ mode) => conformanceJson(readNode(kind9(explicitBody(walk, mode, [], [...xs, ...ys, ...zs])))).groups[0].shell.grid;
  assert.deepEqual(grid(1), [[0, 0, 0], [4, 0, 0], [0, 4, 0], [5, -3, 1]]);
  // without the bit: predicted by the naming triangle's i0 = corner 1 (4, 0, 0)
  assert.deepEqual(grid(0), [[0, 0, 0], [4, 0, 0], [0, 4, 0], [5, 1, 1]]);
  // with tables, the indices: x values (0, 4, 5), y (-3, 0, 4), z (0, 1)
  const tables = [3, 0, 3, 0, 3, zigzag(-3), 2, 3, 2, 0, 0];
  // indices: corner 0 (0, 1, 0), 1 (1, 1, 0), 2 (0, 2, 0), 3 (2, 0, 1);
  // parallelogram of corner 3: (1 + 0 - 0, 1 + 1 - 2, 0) = (1, 0, 0): residuals (+1, 0, +1)
  const ix = [0, 2, 1, 2]; // 0, +1, -1, +1
  const iy = [2, 0, 2, 0]; // 1, 0, +1, 0
  const iz = [0, 0, 0, 2]; // 0, 0, 0, +1
  const g3 = conformanceJson(readNode(kind9(explicitBody(walk, 3, tables, [...ix, ...iy, ...iz])))).groups[0].shell.grid;
  assert.deepEqual(g3, [[0, 0, 0], [4, 0, 0], [0, 4, 0], [5, -3, 1]]);
});

test('§9.3, §5: kind 9 in 4.1 and later minors; in 4.0 and 3.4 unknown; kind 10 in 4.2 and later, unknown in 4.0 and 4.1; kind 12 unknown in 4.2, skipped in 4.3', () => {
  const enc = encode(torus(), { mode: 1 });
  const data = enc.kind9;
  assert.deepEqual(readNode(kind9(data)).findings, new Set());
  assert.equal(outcome(kind9(data, [4, 0])), 'UNKNOWN_GROUP_KIND');
  assert.equal(outcome(kind9(data, [3, 4])), 'UNKNOWN_GROUP_KIND');
  // a 3.5 file: kind 9 is a kind of a newer minor of major 3, skipped
  const v35 = readNode(kind9(data, [3, 5]));
  assert.deepEqual([...v35.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  // a 4.2 file: kinds 9 and 10 decoded, no finding
  const both = readNode(file({ planes: ONE_PLANE, groups: [{ kind: 9, data }, { kind: 10, data: enc.kind10 }], version: [4, 2] }));
  assert.deepEqual(both.findings, new Set());
  const json = conformanceJson(both);
  assert.deepEqual(json.groups[1].shell, json.groups[0].shell);
  assert.deepEqual(json.groups.map((/** @type {any} */ g) => g.kind), [9, 10]);
  // kind 10 in a 4.0 or 4.1 file: not a kind of the file's version, whose minor this reader knows
  for (const minor of [0, 1]) {
    assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 10, data: enc.kind10 }], version: [4, minor] })), 'UNKNOWN_GROUP_KIND');
  }
  assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 10, data: [] }], version: [4, 1] })), 'UNKNOWN_GROUP_KIND');
  assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 10, data: enc.kind10 }], version: [3, 4] })), 'UNKNOWN_GROUP_KIND');
  // kind 10 read in 4.2: an empty kind data ends inside its counts
  assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 10, data: [] }], version: [4, 2] })), 'BAD_PAYLOAD');
  // kind 12, a kind of no version (11 is a copy, §9.15, tested in copies.test.mjs): unknown in
  // 4.2 (the newest minor known), skipped in 4.3 with its common body checked
  assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 12, data: [1, 2, 3] }], version: [4, 2] })), 'UNKNOWN_GROUP_KIND');
  assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 255, data: [] }], version: [4, 2] })), 'UNKNOWN_GROUP_KIND');
  const v43 = file({ planes: ONE_PLANE, groups: [{ kind: 10, data: enc.kind10 }, { kind: 12, data: [1, 2, 3] }], version: [4, 3] });
  const r = readNode(v43);
  assert.deepEqual([...r.findings].sort(), ['NEWER_MINOR_VERSION', 'SKIPPED_GROUP_KIND']);
  assert.equal(r.meshes[1], null);
  assert.ok(/** @type {any} */ (r.meshes[0]).indices.length > 0);
  assert.equal(/** @type {any} */ (conformanceJson(r).geometry).groups[1], null);
  assert.deepEqual(conformanceJson(r).groups[0].shell, json.groups[0].shell);
  // a 4.2 file without kind 10 reads alike; kinds 0-8 are still read in 4.1 and 4.2
  assert.deepEqual(conformanceJson(readNode(kind9(data, [4, 2]))).groups[0].shell, json.groups[0].shell);
  for (const minor of [1, 2]) assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 7, data: encode(torus()).tree }], version: [4, minor] })), 'ok');
});

test('§9.13: linear time on large and hostile walks', () => {
  // a torus of 2 × 60 × 100 = 12,000 triangles
  const enc = encode(torus(60, 100), { mode: 1 });
  const bytes = kind9(enc.kind9);
  let t0 = performance.now();
  const f = readNode(bytes);
  const ms = performance.now() - t0;
  assert.equal(/** @type {any} */ (f.meshes[0]).indices.length, 3 * 12000);
  assert.ok(ms < HANG_MS, `${ms} ms`);
  // a fan of 200,000 triangles around corner 0, each third corner new (a chain of attached
  // triangles, each with its edge 2 as its one child): corner 0 gathers open edges, and a last
  // triangle names one through left; then many roots over old corners, each leaving 3 open edges
  const T = 200000;
  const symbols = [3, ...new Array(T - 2).fill(8), 2];
  const fan = explicitBody({ V: T + 1, T, symbols, escapes: [0, 0, 0], flags: [] });
  t0 = performance.now();
  assert.equal(outcome(kind9(fan)), 'ok');
  const many = 100000;
  const roots = explicitBody({ V: 3, T: many, symbols: new Array(many).fill(0), escapes: [0, 0, 0, ...new Array(many - 1).fill([3, 2, 1]).flat()], flags: [] });
  assert.equal(outcome(kind9(roots)), 'ok');
  assert.ok(performance.now() - t0 < HANG_MS, `${performance.now() - t0} ms`);
});

// ---------------------------------------------------------------------------------------------
// Kind 10 (§9.14, version 4.2): shell walks with multi-parallelograms

/**
 * An icosahedron subdivided `levels` times onto a sphere of radius r, corners rounded to integers
 * (every corner explicit, every triangle free), counter-clockwise seen from outside.
 */
function icosphere(levels = 2, r = 1000) {
  const t = (1 + Math.sqrt(5)) / 2;
  /** @type {number[][]} */
  const points = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]];
  let tris = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6], [7, 1, 8],
    [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]];
  for (let l = 0; l < levels; l++) {
    /** @type {Map<string, number>} */
    const mid = new Map();
    const m = (/** @type {number} */ a, /** @type {number} */ b) => {
      const key = a < b ? `${a},${b}` : `${b},${a}`;
      if (!mid.has(key)) { mid.set(key, points.length); points.push(points[a].map((c, i) => (c + points[b][i]) / 2)); }
      return /** @type {number} */ (mid.get(key));
    };
    tris = tris.flatMap(([a, b, c]) => {
      const [ab, bc, ca] = [m(a, b), m(b, c), m(c, a)];
      return [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]];
    });
  }
  const coords = points.map((p) => {
    const l = Math.hypot(...p);
    return p.map((c) => Math.round((r * c) / l));
  });
  return { tris, face: tris.map(() => -1), coords };
}

test('§9.14: kind 10 round trips: an icosphere, a torus, an open grid, pieces, a cube of named and explicit corners; four modes', () => {
  const histogram = [0, 0, 0, 0, 0];
  let negativeRounded = 0;
  let differs = 0;
  // the icosphere is closed and manifold: every directed edge once, its reverse present
  const ico = icosphere();
  const edges = new Set(ico.tris.flatMap((t) => [0, 1, 2].map((e) => `${t[e]},${t[(e + 1) % 3]}`)));
  assert.equal(edges.size, 3 * ico.tris.length);
  for (const e of edges) assert.ok(edges.has(e.split(',').reverse().join()));
  const cases = /** @type {[number[][], Mesh, Parameters<typeof encode>[1]][]} */ ([
    [ONE_PLANE, ico, {}], [ONE_PLANE, icosphere(1, 50), { reverse: true }], [ONE_PLANE, torus(20, 12), {}], [ONE_PLANE, torus(9, 7), { oneChild: true }],
    [ONE_PLANE, torus(), { drop: 7 }], [ONE_PLANE, grid(9, 5), {}], [ONE_PLANE, grid(), { drop: 3, reverse: true }], [ONE_PLANE, pieces(), {}],
    [CUBE_PLANES, cube([0, 3, 5, 6, 7]), {}], [CUBE_PLANES, cube([1, 2, 4, 7]), { reverse: true }], [ONE_PLANE, ico, { escapeAll: true }],
  ]);
  for (const [planes, mesh, options] of cases) {
    for (const mode of [0, 1, 2, 3]) {
      const { enc, shell } = roundTrip(planes, mesh, { ...options, mode }, 10);
      const m = /** @type {NonNullable<typeof enc.multi>} */ (enc.multi);
      m.histogram.forEach((c, n) => { histogram[n] += c; });
      negativeRounded += m.negativeRounded;
      // the reference decoding of the residuals gives back the values encoded
      const ref = decode10(enc.walk, m.residuals.map(zigzagBig));
      assert.notEqual(ref, 'BAD_GROUP_STRUCTURE');
      for (const k of enc.walk.ex) {
        for (let a = 0; a < 3; a++) assert.equal(/** @type {Map<number, bigint[]>} */ (ref).get(k)?.[a], enc.walk.tables ? BigInt(enc.walk.tables[a].indexOf(/** @type {number[]} */ (mesh.coords[enc.source[k]])[a])) : BigInt(/** @type {number[]} */ (mesh.coords[enc.source[k]])[a]));
      }
      // the same residuals read as kind 9 decode elsewhere wherever some corner has a parallelogram
      if (m.histogram.slice(1).some((c) => c > 0)) {
        assert.notDeepEqual(enc.kind10, enc.kind9);
        const as9 = file({ planes, groups: [{ kind: 9, data: enc.kind10 }] });
        const o = outcome(as9);
        if (o !== 'ok' || JSON.stringify(conformanceJson(readNode(as9)).groups[0].shell) !== JSON.stringify(shell)) differs++;
      }
    }
  }
  // every count of parallelograms met, and floors of negative sums that round
  for (let n = 0; n <= 4; n++) assert.ok(histogram[n] > 0, `${histogram}`);
  assert.ok(negativeRounded > 0);
  assert.ok(differs > 20, `${differs}`);
});

test('§9.14: kind 10 beside kind 9 in one file, compressed payloads, and the parallelograms of the reader against the test\'s', async () => {
  const enc = encode(icosphere(2), { mode: 1 });
  const bytes = file({ planes: ONE_PLANE, groups: [{ kind: 10, data: enc.kind10, method: 2 }, { kind: 10, data: enc.kind10, method: 1 }, { kind: 9, data: enc.kind9 }], version: [4, 2] });
  const json = conformanceJson(readNode(bytes));
  assert.deepEqual(json.groups[0].shell, json.groups[2].shell);
  assert.deepEqual(json.groups[1].shell, json.groups[2].shell);
  assert.deepEqual(conformanceJson(readBrowser(bytes)), json);
  // the reader's parallelograms (sorted runs, binary search) equal the test's (a Map), on walks
  // with several roots over old corners, non-manifold pieces and named corners
  const { parallelograms } = await import('../src/shelltree.mjs');
  const meshes = [icosphere(1), torus(), grid(), pieces(), cube([0, 3, 5, 6, 7]), fins()];
  for (const [i, mesh] of meshes.entries()) {
    for (const drop of [0, 5 + i]) {
      const e = encode(mesh, { drop });
      const w = e.walk;
      const want = multiGrams(w);
      const got = parallelograms(w.explicit.length, w.tris.length, Uint8Array.from(w.explicit, Number), Uint32Array.from(w.tris.flat()));
      for (let k = 0; k < w.explicit.length; k++) {
        const list = [];
        for (let q = 0; q < got.count[k]; q++) list.push([...got.abc.subarray(12 * k + 3 * q, 12 * k + 3 * q + 3)]);
        assert.deepEqual(list, want[k], `mesh ${i} corner ${k}`);
      }
    }
  }
});

/**
 * A non-manifold mesh: three triangles on edge (0, 1) one way, two the other (the far corner of a
 * directed edge is the first triangle's), a strip beside them; every corner explicit.
 */
function fins() {
  const tris = [[0, 1, 2], [1, 0, 3], [1, 0, 4], [0, 1, 5], [1, 0, 6], [2, 1, 7], [7, 1, 8], [3, 0, 9], [9, 0, 4], [5, 1, 6]];
  const coords = [[0, 0, 0], [10, 0, 0], [5, 8, 0], [5, -8, 1], [4, -3, 9], [6, 5, -7], [3, -1, -9], [14, 9, 2], [20, 1, -1], [-3, -9, 4]];
  return { tris, face: tris.map(() => -1), coords };
}

test('§9.14 by hand: the parallelograms of the triangles around a corner, averaged, the division rounding toward −∞', () => {
  // root (0 1 2), children across edges 0 and 1 (list 4); (1 0 3) new, its child across its edge 2
  // (3 -> 1): (1 3 4) new; then across the root's edge 1: (2 1 4) by left (the newest open edge
  // ending at 1 is (4, 1))
  const walk = { V: 5, T: 4, symbols: [4, 8, 0, 1], escapes: [0, 0, 0], flags: [] };
  assert.deepEqual(trianglesOf(walk), [[0, 1, 2], [1, 0, 3], [1, 3, 4], [2, 1, 4]]);
  // corner 3: (1 0 3) gives a = 1, b = 0, and (0, 1) is the root's, far corner 2: one
  // parallelogram, 1 + 0 - 2. Corner 4: (1 3 4) gives (1, 3, far corner of (1, 3) = 0 from (1 0 3)),
  // (2 1 4) gives (2, 1, 0 from the root): S = g1 + g3 - g0 + g2 + g1 - g0, n = 2.
  // Corners 0-2 have none: a root's, predicted by the previous explicit corner.
  // Values: 0 (0,0,0), 1 (10,-7,1), 2 (3,5,-2), 3 = (7,-12,3) + (1,-1,0) = (8,-13,3),
  // 4: S = (31, -22, 3), ⌊(S + 1) / 2⌋ = (16, -11, 2) (truncation would give -10), residual 0
  const xs = [0, 20, 13, 2, 0];
  const ys = [0, 13, 24, 1, 0];
  const zs = [0, 2, 5, 0, 0];
  const g = (/** @type {number} */ kind, /** @type {number} */ mode) => conformanceJson(readNode(file({ planes: ONE_PLANE, groups: [{ kind, data: explicitBody(walk, mode, [], [...xs, ...ys, ...zs]) }], version: [4, 2] }))).groups[0].shell.grid;
  const want = [[0, 0, 0], [10, -7, 1], [3, 5, -2], [8, -13, 3], [16, -11, 2]];
  assert.deepEqual(g(10, 0), want);
  assert.deepEqual(g(10, 1), want); // every corner with a parallelogram or none of §9.12's
  // kind 9 reads the same residuals otherwise: corner 3 from i0 = 1 (mode 0), then corner 4 from 1
  assert.deepEqual(g(9, 0), [[0, 0, 0], [10, -7, 1], [3, 5, -2], [11, -8, 1], [10, -7, 1]]);
  // a non-manifold edge: the far corner is the first triangle's with the reverse edge (checked
  // against the test's reference encoding rather than by hand)
  const mesh = fins();
  for (const mode of [0, 1]) roundTrip(ONE_PLANE, mesh, { mode }, 10);
  const e = encode(mesh);
  assert.ok(/** @type {NonNullable<typeof e.multi>} */ (e.multi).histogram[0] < e.E);
});

test('§9.14 hostile: values near 2^52, sums past 2^53, a value pushed past 2^52, an index outside its table', () => {
  const walk = { V: 5, T: 4, symbols: [4, 8, 0, 1], escapes: [0, 0, 0], flags: [] };
  const Z = 2 ** 52;
  const go = (/** @type {(number | bigint)[]} */ xs, mode = 0, /** @type {number[]} */ tables = []) => {
    const data = explicitBody(walk, mode, tables, [...xs, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
    const bytes = file({ planes: ONE_PLANE, groups: [{ kind: 10, data }], version: [4, 2] });
    const o = outcome(bytes);
    return o === 'ok' ? conformanceJson(readNode(bytes)).groups[0].shell.grid.map((/** @type {number[]} */ c) => c[0]) : o;
  };
  const zz = (/** @type {number} */ v) => zigzagBig(BigInt(v));
  // x: g0 = -2^52 + 1, g1 = 1, g2 = 2^52 - 1, g3 = g1 + g0 - g2 + 2^52 = 3 - 2^52; corner 4:
  // S = (g1 + g3 - g0) + (g2 + g1 - g0) = 3 + (2^53 - 1): its partial sums pass 2^53, where binary64
  // rounds (S + 1 = 2^53 + 3 would round to 2^53 + 4 and the prediction to 2^52 + 2)
  const head = [zz(-Z + 1), zz(Z), zz(Z - 2), zz(Z)];
  assert.deepEqual(go([...head, zz(-1)]), [-Z + 1, 1, Z - 1, 3 - Z, Z]);
  assert.deepEqual(go([...head, zz(-2)]), [-Z + 1, 1, Z - 1, 3 - Z, Z - 1]);
  assert.deepEqual(go([...head, zz(-Z)]), [-Z + 1, 1, Z - 1, 3 - Z, 1]);
  assert.equal(go([...head, zz(0)]), 'BAD_GROUP_STRUCTURE'); // 2^52 + 1
  assert.equal(go([...head, zz(Z)]), 'BAD_GROUP_STRUCTURE');
  assert.equal(go([...head, zz(-Z) + 2n]), 'BAD_GROUP_STRUCTURE'); // a residual of -2^52 - 1
  assert.equal(go([...head, 2n ** 64n - 1n]), 'BAD_GROUP_STRUCTURE');
  // a value pushed past 2^52 earlier in the chain by a residual within it: corner 3 is
  // g1 + g0 - g2 + r3 = 3 - 2^53 + r3
  assert.deepEqual(go([zz(-Z + 1), zz(Z), zz(Z - 2), zz(Z - 2), zz(0)]), [-Z + 1, 1, Z - 1, 1 - Z, Z]); // S = 2^53
  assert.equal(go([zz(-Z + 1), zz(Z), zz(Z - 2), zz(Z - 4), zz(0)]), 'BAD_GROUP_STRUCTURE'); // -2^52 - 1
  assert.equal(go([zz(-Z + 1), zz(Z), zz(Z), zz(-Z), zz(0)]), 'BAD_GROUP_STRUCTURE'); // corner 2 at 2^52 + 1
  // tables: x indices 0, 2, 1, 3 (residuals 0, +2, -1, +2), corner 4 ⌊(8 + 1) / 2⌋ = 4 plus its residual,
  // in a table of 5 values (-10, -9, -7, -4, 0)
  const tables = [5, zigzag(-10), 0, 1, 2, 3, 1, 0, 1, 0];
  assert.deepEqual(go([0, 4, 1, 4, 0], 2, tables), [-10, -7, -9, -4, 0]);
  assert.deepEqual(go([0, 4, 1, 4, 1], 2, tables), [-10, -7, -9, -4, -4]);
  assert.deepEqual(go([0, 4, 1, 4, 7], 2, tables), [-10, -7, -9, -4, -10]);
  assert.equal(go([0, 4, 1, 4, 2], 2, tables), 'BAD_GROUP_STRUCTURE'); // index 5
  assert.equal(go([0, 4, 1, 4, 9], 2, tables), 'BAD_GROUP_STRUCTURE'); // index -1
  assert.equal(go([0, 4, 1, 4, zz(-Z)], 2, tables), 'BAD_GROUP_STRUCTURE');
  assert.equal(go([0, 4, 1, 4, zz(Z) + 1n], 2, tables), 'BAD_GROUP_STRUCTURE');
  assert.equal(go([0, 4, 1, 4, 2n ** 64n - 1n], 2, tables), 'BAD_GROUP_STRUCTURE');
  assert.equal(go([0, 4, 1, 6, 0], 2, tables), 'BAD_GROUP_STRUCTURE'); // corner 3 at index 4, corner 4 at 5
  assert.deepEqual(go([0, 4, 1, 6, 1], 2, tables), [-10, -7, -9, 0, 0]); // 5 - 1
});

test('§9.14 hostile: residuals near 2^52 against the reference decoding, in every mode, on several walks', () => {
  let seed = 12345;
  const rnd = () => {
    seed = (Math.imul(seed, 1103515245) + 12345) >>> 0;
    return seed / 4294967296;
  };
  const L = 2n ** 52n;
  const extremes = [L, L - 1n, -L, -L + 1n, 0n, 1n, -1n, L / 2n, -L / 3n];
  const outcomes = { ok: 0, bad: 0 };
  for (const mesh of [icosphere(1, 100), torus(6, 4), grid(4, 3), fins()]) {
    for (const mode of [0, 1, 2, 3]) {
      const enc = encode(mesh, { mode });
      const w = enc.walk;
      const grams = multiGrams(w);
      const E = w.ex.length;
      for (let trial = 0; trial < 12; trial++) {
        // per corner a target value (extreme, or random within the range; with tables an index,
        // sometimes just outside its table), the residual that reaches it from the prediction,
        // clamped to ±2^52 (then the value misses the target, and may pass 2^52)
        /** @type {bigint[]} */
        const zzs = new Array(3 * E);
        /** @type {Map<number, bigint[]>} */
        const values = new Map();
        const g = (/** @type {number} */ k, /** @type {number} */ a) => /** @type {bigint[]} */ (values.get(k))[a];
        let previous = -1;
        for (let e = 0; e < E; e++) {
          const k = w.ex[e];
          values.set(k, [0n, 0n, 0n]);
          for (let a = 0; a < 3; a++) {
            let target;
            if (w.tables) {
              const C = w.tables[a].length;
              target = BigInt(Math.floor(rnd() * (C + (trial % 3 === 0 ? 0.02 * E : 0))) - (rnd() < 0.01 * (trial % 3) ? 1 : 0));
            } else {
              target = rnd() < 0.5 ? extremes[Math.floor(rnd() * extremes.length)] : BigInt(Math.floor((rnd() * 2 - 1) * 2 ** 52));
            }
            let r = target - predict10(w, grams, k, a, g, previous);
            if (r > L) r = L;
            if (r < -L) r = -L;
            zzs[a * E + e] = zigzagBig(r);
            /** @type {bigint[]} */ (values.get(k))[a] = predict10(w, grams, k, a, g, previous) + r;
          }
          previous = k;
        }
        const want = decode10(w, zzs);
        const bytes = file({ planes: ONE_PLANE, groups: [{ kind: 10, data: [...enc.head, ...varints(zzs)] }], version: [4, 2] });
        const got = outcome(bytes);
        if (want === 'BAD_GROUP_STRUCTURE') {
          assert.equal(got, want, `mode ${mode} trial ${trial}`);
          outcomes.bad++;
          continue;
        }
        assert.equal(got, 'ok', `mode ${mode} trial ${trial}`);
        outcomes.ok++;
        const grid = conformanceJson(readNode(bytes)).groups[0].shell.grid;
        w.ex.forEach((k, e) => {
          const v = /** @type {bigint[]} */ (want.get(k));
          const c = w.tables ? v.map((x, a) => /** @type {number[][]} */ (w.tables)[a][Number(x)]) : v.map(Number);
          assert.deepEqual(grid[e], c, `mode ${mode} trial ${trial} corner ${k}`);
        });
      }
    }
  }
  assert.ok(outcomes.ok > 20 && outcomes.bad > 20, JSON.stringify(outcomes));
});

test('§9.14: linear time on large and hostile walks', () => {
  const enc = encode(torus(60, 100), { mode: 1 });
  let t0 = performance.now();
  const f = readNode(file({ planes: ONE_PLANE, groups: [{ kind: 10, data: enc.kind10 }], version: [4, 2] }));
  assert.equal(/** @type {any} */ (f.meshes[0]).indices.length, 3 * 12000);
  assert.ok(performance.now() - t0 < HANG_MS, `${performance.now() - t0} ms`);
  // a fan of 200,000 triangles around corner 0, every corner explicit: corner 0's edges are one
  // long run, each later corner finds its far corners by binary search in it
  const T = 200000;
  const symbols = [3, ...new Array(T - 2).fill(8), 2];
  const fan = explicitBody({ V: T + 1, T, symbols, escapes: [0, 0, 0], flags: [] }, 1);
  t0 = performance.now();
  assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 10, data: fan }], version: [4, 2] })), 'ok');
  // many roots over three old corners: one directed edge held by 100,000 triangles
  const many = 100000;
  const roots = explicitBody({ V: 3, T: many, symbols: new Array(many).fill(0), escapes: [0, 0, 0, ...new Array(many - 1).fill([3, 2, 1]).flat()], flags: [] });
  assert.equal(outcome(file({ planes: ONE_PLANE, groups: [{ kind: 10, data: roots }], version: [4, 2] })), 'ok');
  assert.ok(performance.now() - t0 < HANG_MS, `${performance.now() - t0} ms`);
});
