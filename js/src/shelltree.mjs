/**
 * Shell trees (kind 7, spec §9.11, and kind 8, §9.12, whose explicit corners parallelograms predict),
 * read into the Shell structure of shells.mjs.
 *
 * The spec lets a reader decode the triangles in order (a parent precedes its children) or by
 * pointer jumping; planefmt jumps pointers because numpy has no fast loop. Here one pass in
 * triangle order does the same work in linear time, which is what a loop in JavaScript is good
 * at (the corners each triangle takes from its parent are known when the loop reaches it).
 *
 * shellTreeRest, everything after the corner codes, is shared with shell walks (kind 9, §9.13, kind
 * 10, §9.14, kind 12, §9.16, and kind 13, §9.17, shellwalk.mjs), whose links and corners come from a
 * walk instead; kind 10's multi-parallelogram prediction (parallelograms, averaged), kind 12's
 * reflection (the turn of a chain of steps) and kind 13's step source (the later-named gate corner)
 * are here, with the other predictions.
 */
import { fail } from './errors.mjs';
import { NO_CHARGE } from './budget.mjs';
import { unzigzag, readBits } from './varint.mjs';
import { readVarints, readGrid, checkGrid, MAX_COORD } from './shells.mjs';

/**
 * @param {import('./varint.mjs').Cursor} b
 * @param {Uint8Array} roles
 * @param {boolean} [parallelogram] kind 8 (§9.12)
 * @param {boolean} [f32Grid] version 5: the grid in f32 (§9.10)
 * @returns {import('./shells.mjs').Shell}
 * @param {import('./budget.mjs').Charge} [charge] takes the declared counts once checked, before
 *   anything of their size is allocated (§12.4)
 */
export function readShellTree(b, roles, parallelogram = false, f32Grid = false, charge = NO_CHARGE) {
  const m = roles.length;
  const V = b.varint();
  const T = b.varint();
  const left = b.left;
  if (V < 3 || V > 8 * left || T < 1 || 3 * T > left) fail('BAD_GROUP_STRUCTURE', `counts V=${V} T=${T} for ${left} bytes`);
  charge(V, T);
  const links = readVarints(b, T);
  let roots = 0;
  for (let j = 0; j < T; j++) if (links[j] === 0) roots++;
  const codes = readVarints(b, T + 2 * roots);
  const faceCodes = readVarints(b, T);
  const explicit = readBits(b, V);

  // links and corner codes: the triangles, in order
  // the codes name at most T + 2R corners, so a larger V fails below (n ≠ V) whatever the rest
  // holds: refused here, before anything of V's size is allocated beyond the flags
  if (V > T + 2 * roots) fail('BAD_GROUP_STRUCTURE', `${V} corners, at most ${T + 2 * roots} named`);
  const tri = new Uint32Array(3 * T);
  const namer = new Int32Array(V); // the triangle whose code names each corner anew, -1 for a root
  const parent = new Int32Array(T);
  const opposite = new Int32Array(T); // the parent's corner off the shared edge, -1 for a root
  let n = 0;
  let ci = 0;
  // every bound below is checked before the integer arithmetic it makes safe
  for (let j = 0; j < T; j++) {
    const link = links[j];
    let i0;
    let i1;
    let i2;
    if (link === 0) {
      parent[j] = -1;
      opposite[j] = -1;
      const c0 = codes[ci];
      const c1 = codes[ci + 1];
      const c2 = codes[ci + 2];
      ci += 3;
      if (c0 > n) fail('BAD_GROUP_STRUCTURE', `root ${j} names a corner below 0`);
      if (c0 === 0) namer[(i0 = n++)] = -1;
      else i0 = n - c0;
      if (c1 > n) fail('BAD_GROUP_STRUCTURE', `root ${j} names a corner below 0`);
      if (c1 === 0) namer[(i1 = n++)] = -1;
      else i1 = n - c1;
      if (c2 > n) fail('BAD_GROUP_STRUCTURE', `root ${j} names a corner below 0`);
      if (c2 === 0) namer[(i2 = n++)] = -1;
      else i2 = n - c2;
      if (n > V) fail('BAD_GROUP_STRUCTURE', `more than ${V} corners named`);
    } else {
      if (link > 3 * j) fail('BAD_GROUP_STRUCTURE', `triangle ${j} links past the first triangle`);
      const d = (((link - 1) / 3) | 0) + 1;
      const e = link - 1 - 3 * (d - 1);
      const p = j - d;
      parent[j] = p;
      i0 = tri[3 * p + (e === 2 ? 0 : e + 1)];
      i1 = tri[3 * p + e];
      opposite[j] = tri[3 * p + (e === 0 ? 2 : e - 1)];
      const k = codes[ci++];
      if (k === 0) {
        if (n >= V) fail('BAD_GROUP_STRUCTURE', `more than ${V} corners named`);
        namer[(i2 = n++)] = j;
      } else {
        // |z(k - 1)| < n for any corner named before, so k ≤ 2n keeps to small integers
        if (k > 2 * n) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names a corner not named before`);
        const z = k - 1;
        i2 = i1 + (z & 1 ? -(z + 1) / 2 : z / 2); // z < 2^32: its low bit survives & 1
        if (i2 < 0 || i2 >= n) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names a corner not named before`);
      }
    }
    if (i0 === i1 || i1 === i2 || i0 === i2) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names one corner twice`);
    tri[3 * j] = i0;
    tri[3 * j + 1] = i1;
    tri[3 * j + 2] = i2;
  }
  if (n !== V) fail('BAD_GROUP_STRUCTURE', `${n} corners named, ${V} declared`);

  return shellTreeRest(b, roles, { V, T, explicit, tri, namer, parent, opposite, faceCodes }, { parallelogram, f32Grid });
}

/**
 * What a shell tree (§9.11, §9.12) or a shell walk (§9.13) holds after its corner codes, once its
 * triangles are known: the faces (read before, checked here), named corners and their picks, and
 * the explicit corners (for a walk: after its mode byte, with per-axis value tables where the mode
 * says so).
 * @param {import('./varint.mjs').Cursor} b
 * @param {Uint8Array} roles
 * @param {object} s the triangles
 * @param {number} s.V corners
 * @param {number} s.T triangles
 * @param {Uint8Array} s.explicit 1 where a corner is explicit
 * @param {Uint32Array} s.tri 3 corners per triangle
 * @param {Int32Array} s.namer the attached triangle whose code names each corner anew, -1 for a root
 * @param {Int32Array} s.parent per triangle, -1 for a root
 * @param {Int32Array} s.opposite per triangle, the parent's corner off the shared edge, -1 for a root
 * @param {Float64Array} s.faceCodes per triangle, as read
 * @param {{parallelogram: boolean, walk?: boolean, multi?: boolean, reflect?: boolean, later?: boolean, f32Grid?: boolean}} how kind 8
 *   (parallelogram), kind 9 (walk: a mode byte decides both), kind 10 (walk and multi: §9.14's
 *   averaged parallelograms first), kind 12 (walk and reflect: §9.16's turn first, where a chain
 *   turns), kind 13 (walk and later: §9.17's predictor, the naming triangle's max(i0, i1) rather
 *   than its i0; the parallelogram unchanged); f32Grid: the grid in f32 (version 5, §9.10)
 * @returns {import('./shells.mjs').Shell}
 */
export function shellTreeRest(b, roles, { V, T, explicit, tri, namer, parent, opposite, faceCodes }, { parallelogram, walk = false, multi = false, reflect = false, later = false, f32Grid = false }) {
  const m = roles.length;
  // faces: 0 the parent's (the previous triangle's for a root), 1 free, r + 2 reference r
  const face = new Int32Array(T);
  for (let j = 0; j < T; j++) {
    const fc = faceCodes[j];
    if (fc === 0) face[j] = parent[j] >= 0 ? face[parent[j]] : j > 0 ? face[j - 1] : -1;
    else if (fc === 1) face[j] = -1;
    else {
      if (fc > m + 1 || roles[fc - 2]) fail('BAD_GROUP_STRUCTURE', `face code ${fc}`);
      face[j] = fc - 2;
    }
  }

  // the face planes of each named corner, ascending and distinct, in CSR form
  const start = new Int32Array(V + 1);
  for (let j = 0; j < T; j++) {
    if (face[j] < 0) continue;
    for (let s = 0; s < 3; s++) if (!explicit[tri[3 * j + s]]) start[tri[3 * j + s] + 1]++;
  }
  for (let k = 0; k < V; k++) start[k + 1] += start[k];
  const fill = start.slice(0, V);
  const planesOf = new Int32Array(start[V]);
  for (let j = 0; j < T; j++) {
    if (face[j] < 0) continue;
    for (let s = 0; s < 3; s++) {
      const k = tri[3 * j + s];
      if (!explicit[k]) planesOf[fill[k]++] = face[j];
    }
  }
  const distinct = new Int32Array(V);
  let W = 0;
  for (let k = 0; k < V; k++) {
    if (explicit[k]) continue;
    // insertion sort of a few entries in place, then the distinct ones to the front
    const lo = start[k];
    const hi = start[k + 1];
    for (let i = lo + 1; i < hi; i++) {
      const x = planesOf[i];
      let q = i - 1;
      while (q >= lo && planesOf[q] > x) {
        planesOf[q + 1] = planesOf[q];
        q--;
      }
      planesOf[q + 1] = x;
    }
    let u = 0;
    for (let i = lo; i < hi; i++) if (i === lo || planesOf[i] !== planesOf[i - 1]) planesOf[lo + u++] = planesOf[i];
    distinct[k] = u;
    if (u > 3) W++;
  }

  const picks = readVarints(b, 3 * W);
  let E = 0;
  for (let k = 0; k < V; k++) E += explicit[k];
  // a walk's mode (§9.13): bit 0 parallelogram, bit 1 tables; bits 2-7 checked with the rest
  const mode = walk && E > 0 ? b.u8() : 0;
  if (walk) parallelogram = (mode & 1) !== 0;
  const grid = E > 0 ? readGrid(b, f32Grid) : null;
  /** @type {{first: number, gaps: Float64Array}[] | null} per axis, as read */
  let tablesRead = null;
  if (walk && E > 0 && mode & 2) {
    tablesRead = [];
    for (let a = 0; a < 3; a++) {
      // a count, checked as it is read, before the values it counts (§12.1)
      const C = b.varint();
      if (C < 1 || C > E) fail('BAD_GROUP_STRUCTURE', `a table of ${C} values for ${E} explicit corners`);
      const first = b.varint();
      tablesRead.push({ first, gaps: readVarints(b, C - 1) });
    }
  }
  const residuals = readVarints(b, 3 * E);
  if (b.left > 0) fail('BAD_GROUP_STRUCTURE', `${b.left} bytes after the last field`);

  const cornerPlanes = new Int32Array(3 * V).fill(-1);
  for (let k = 0, w = 0; k < V; k++) {
    if (explicit[k]) continue;
    const u = distinct[k];
    if (u < 3) fail('BAD_GROUP_STRUCTURE', `named corner ${k} on ${u} face planes`);
    let [i, j, l] = [0, 1, 2];
    if (u > 3) {
      [i, j, l] = [picks[3 * w], picks[3 * w + 1], picks[3 * w + 2]];
      w++;
      if (!(i < j && j < l && l < u)) fail('BAD_GROUP_STRUCTURE', `picks ${i} ${j} ${l} of corner ${k} on ${u} planes`);
    }
    const at = start[k];
    cornerPlanes[3 * k] = planesOf[at + i];
    cornerPlanes[3 * k + 1] = planesOf[at + j];
    cornerPlanes[3 * k + 2] = planesOf[at + l];
  }
  if (mode > 3) fail('BAD_GROUP_STRUCTURE', `mode ${mode}: a bit above 1 set`);
  if (grid) checkGrid(grid);
  // the tables' values: the first, then each the previous plus g + 1, all within 2^52
  const tables = tablesRead && tablesRead.map(({ first, gaps }) => {
    const values = new Float64Array(gaps.length + 1);
    let v = unzigzag(first);
    if (v > MAX_COORD || v < -MAX_COORD) fail('BAD_GROUP_STRUCTURE', 'a table value beyond 2^52');
    values[0] = v;
    for (let i = 0; i < gaps.length; i++) {
      // v + g + 1 ≤ 2^52 as g ≤ 2^52 - 1 - v, both sides exact (g is exact up to 2^53, and saturated above it)
      if (gaps[i] > MAX_COORD - 1 - v) fail('BAD_GROUP_STRUCTURE', 'a table value beyond 2^52');
      v += gaps[i] + 1;
      values[i + 1] = v;
    }
    return values;
  });

  // explicit corners: predicted from the naming triangle's first corner (kind 13: the later-named of
  // its first two), else the previous explicit one; kind 8 (a walk's parallelogram bit): by the
  // parallelogram i0 + i1 - opposite where all three are explicit. What is predicted and resolved is
  // the integer coordinates, or with a walk's tables the indices into each axis's table. Every term is
  // within 2^52 (checked as made), so each sum is exact in binary64.
  // kind 10 (§9.14): up to four parallelograms (a, b, c) per explicit corner, averaged where there are any
  const multiGrams = multi && E > 0 ? parallelograms(V, T, explicit, tri) : null;
  // kind 12 (§9.16): each explicit corner's step source p (the §9.11 predictor, whatever the mode),
  // and the turn of a chain a = p(k), b = p(a), c = p(b) where it turns
  const steps = reflect && E > 0 ? new Int32Array(V) : null;
  const q = new Float64Array(3);
  const values = new Float64Array(3 * V);
  const coords = tables ? new Float64Array(3 * V) : values;
  let previous = -1;
  for (let k = 0, e = 0; k < V; k++) {
    if (!explicit[k]) continue;
    const t = namer[k];
    // the gate corner stepped from: i0 (§9.11), or for kind 13 the later-named of i0 and i1 (§9.17)
    const from = t < 0 ? -1 : later ? Math.max(tri[3 * t], tri[3 * t + 1]) : tri[3 * t];
    const pred = from >= 0 && explicit[from] ? from : previous;
    let turns = false;
    if (steps) {
      steps[k] = pred;
      // a step source is explicit and below k, so its own step source is set
      const b = pred >= 0 ? steps[pred] : -1;
      const c = b >= 0 ? steps[b] : -1;
      turns = c >= 0 && turn(values, pred, b, c, q);
    }
    const gram = !turns && parallelogram && t >= 0 && explicit[tri[3 * t]] && explicit[tri[3 * t + 1]] && explicit[opposite[t]];
    const grams = multiGrams ? multiGrams.count[k] : 0;
    for (let a = 0; a < 3; a++) {
      const zz = residuals[a * E + e];
      // zigzag in integer arithmetic where it fits (nearly always), else in floating point
      const r = zz < 0x7fffffff ? (zz & 1 ? -((zz + 1) >>> 1) : zz >>> 1) : unzigzag(zz);
      if (grams > 0) {
        if (r > MAX_COORD || r < -MAX_COORD) fail('BAD_GROUP_STRUCTURE', 'residual beyond 2^52');
        const v = averaged(values, /** @type {Int32Array} */ (multiGrams?.abc), 12 * k, grams, a, r);
        if (v > MAX_COORD || v < -MAX_COORD) fail('BAD_GROUP_STRUCTURE', `corner ${k}: a value beyond 2^52`);
        values[3 * k + a] = v;
        if (tables) {
          const table = tables[a];
          if (v < 0 || v >= table.length) fail('BAD_GROUP_STRUCTURE', `corner ${k}: index ${v} outside a table of ${table.length}`);
          coords[3 * k + a] = table[v];
        }
        continue;
      }
      // a turn's base, g(a) + q with |q| ≤ 2^19 + 1, is exact, as is its sum with r where that is within 2^53
      const base = turns ? values[3 * pred + a] + q[a] : gram
        ? values[3 * tri[3 * t] + a] + values[3 * tri[3 * t + 1] + a] - values[3 * opposite[t] + a]
        : pred >= 0 ? values[3 * pred + a] : 0;
      let v = base + r;
      if (gram && (base > MAX_COORD || base < -MAX_COORD)) {
        // a parallelogram past 2^52 may have been rounded: the sum again in exact integers
        const exact = BigInt(values[3 * tri[3 * t] + a]) + BigInt(values[3 * tri[3 * t + 1] + a])
          - BigInt(values[3 * opposite[t] + a]) + BigInt(r);
        const limit = BigInt(MAX_COORD);
        v = exact > limit || exact < -limit ? Infinity : Number(exact);
      }
      if (r > MAX_COORD || r < -MAX_COORD || v > MAX_COORD || v < -MAX_COORD) fail('BAD_GROUP_STRUCTURE', 'coordinate beyond 2^52');
      values[3 * k + a] = v;
      if (tables) {
        const table = tables[a];
        if (v < 0 || v >= table.length) fail('BAD_GROUP_STRUCTURE', `corner ${k}: index ${v} outside a table of ${table.length}`);
        coords[3 * k + a] = table[v];
      }
    }
    previous = k;
    e++;
  }
  return { V, T, explicit, cornerPlanes, grid: coords, origin: grid && grid.origin, step: grid && grid.step, face, tri };
}

const TWO_53 = 2 ** 53;

/** §9.16: a chain turns only where every component of its two steps is within this. */
const STEP_LIMIT = 2 ** 18;

/**
 * §9.16: whether the chain c → b → a of step sources turns, and where it does the turn on each axis
 * i, ⌊(2N_i + D) / (2D)⌋ rounding toward −∞, into q (the prediction is g(a) + q): d1 = g(b) − g(c),
 * d2 = g(a) − g(b), D = d2·d2, N = 2(d1·d2) d2 − D d1. It turns where D > 0 and every component of
 * d1 and d2 is within 2^18. The steps (of values within 2^52), d1·d2 and D (below 2^38) are exact in
 * binary64; N_i reaches 2^58, so N and the quotient in BigInt, whose division truncates toward zero
 * (corrected for a negative numerator; the divisor is positive). |q_i| ≤ |d1| + 1 < 2^19 + 1 (N/D is
 * d1 reflected, of d1's length), exact as a number.
 * @param {Float64Array} values 3 per corner @param {number} a @param {number} b @param {number} c
 * @param {Float64Array} q 3, written where the chain turns
 */
export function turn(values, a, b, c, q) {
  const d1x = values[3 * b] - values[3 * c];
  const d1y = values[3 * b + 1] - values[3 * c + 1];
  const d1z = values[3 * b + 2] - values[3 * c + 2];
  const d2x = values[3 * a] - values[3 * b];
  const d2y = values[3 * a + 1] - values[3 * b + 1];
  const d2z = values[3 * a + 2] - values[3 * b + 2];
  const L = STEP_LIMIT;
  if (!(Math.abs(d1x) <= L && Math.abs(d1y) <= L && Math.abs(d1z) <= L && Math.abs(d2x) <= L && Math.abs(d2y) <= L && Math.abs(d2z) <= L)) return false;
  const D = d2x * d2x + d2y * d2y + d2z * d2z;
  if (D === 0) return false;
  const dot = BigInt(d1x * d2x + d1y * d2y + d1z * d2z);
  const bigD = BigInt(D);
  q[0] = turnAxis(dot, bigD, d1x, d2x);
  q[1] = turnAxis(dot, bigD, d1y, d2y);
  q[2] = turnAxis(dot, bigD, d1z, d2z);
  return true;
}

/**
 * ⌊(2N_i + D) / (2D)⌋ of one axis, N_i = 2(d1·d2) d2_i − D d1_i.
 * @param {bigint} dot d1·d2 @param {bigint} D @param {number} d1 @param {number} d2 the axis's components
 */
function turnAxis(dot, D, d1, d2) {
  const num = 2n * (2n * dot * BigInt(d2) - D * BigInt(d1)) + D;
  const den = 2n * D;
  const quotient = num / den;
  return Number(num < 0n && quotient * den !== num ? quotient - 1n : quotient);
}

/**
 * §9.14: the parallelograms of each explicit corner k, at most four: for each triangle in triangle
 * order and each place s where i_s = k, a = i_(s+1), b = i_(s+2) and c the far corner of (a, b) (the
 * corner off (b, a) of the first triangle, in triangle order, that has the directed edge (b, a)),
 * where c exists and a, b, c are all explicit and all below k.
 *
 * The first triangle of each directed edge is found without a hash table (whose probe lengths a
 * hostile file could choose): the 3T edges, numbered 3j + e in triangle order, are sorted by their
 * end corner and then, stably, by their start corner (two counting sorts, linear in T and V), so
 * that the edges starting at b are one run, ordered by end corner and within one end by triangle:
 * the first triangle with (b, a) is the lower bound of a in b's run (a binary search, log of the
 * run's length).
 * @param {number} V @param {number} T @param {Uint8Array} explicit @param {Uint32Array} tri
 * @returns {{count: Uint8Array, abc: Int32Array}} per corner its number of parallelograms, and
 *   (a, b, c) for each of them at 12k + 3i
 */
export function parallelograms(V, T, explicit, tri) {
  const N = 3 * T;
  /** the end corner of edge i (3j + e: from i_e to i_(e+1) mod 3 of triangle j) @param {number} i */
  const endOf = (i) => tri[i % 3 === 2 ? i - 2 : i + 1];
  const runs = new Int32Array(V + 1);
  const byEnd = new Int32Array(N);
  for (let i = 0; i < N; i++) runs[endOf(i) + 1]++;
  for (let k = 0; k < V; k++) runs[k + 1] += runs[k];
  let at = runs.slice(0, V);
  for (let i = 0; i < N; i++) byEnd[at[endOf(i)]++] = i;
  runs.fill(0);
  for (let i = 0; i < N; i++) runs[tri[i] + 1]++;
  for (let k = 0; k < V; k++) runs[k + 1] += runs[k];
  at = runs.slice(0, V);
  const sorted = new Int32Array(N);
  for (let q = 0; q < N; q++) {
    const i = byEnd[q];
    sorted[at[tri[i]]++] = i;
  }

  const count = new Uint8Array(V);
  const abc = new Int32Array(12 * V);
  for (let j = 0; j < T; j++) {
    for (let s = 0; s < 3; s++) {
      const k = tri[3 * j + s];
      if (!explicit[k] || count[k] === 4) continue;
      const a = tri[3 * j + (s === 2 ? 0 : s + 1)];
      const b = tri[3 * j + (s === 0 ? 2 : s - 1)];
      if (a >= k || b >= k || !explicit[a] || !explicit[b]) continue;
      // the first edge (b, a): the lower bound of a among the ends of b's run
      let lo = runs[b];
      let hi = runs[b + 1];
      while (lo < hi) {
        const mid = (lo + hi) >>> 1;
        if (endOf(sorted[mid]) < a) lo = mid + 1;
        else hi = mid;
      }
      if (lo === runs[b + 1] || endOf(sorted[lo]) !== a) continue;
      const i = sorted[lo]; // edge e of triangle t runs b -> a; its far corner is i_(e+2)
      const c = tri[i % 3 === 0 ? i + 2 : i - 1];
      if (c >= k || !explicit[c]) continue;
      const w = 12 * k + 3 * count[k]++;
      abc[w] = a;
      abc[w + 1] = b;
      abc[w + 2] = c;
    }
  }
  return { count, abc };
}

/**
 * §9.14's prediction on axis `ax`, ⌊(S + ⌊n/2⌋) / n⌋ rounding toward −∞, S the sum of g(a) + g(b) −
 * g(c) over the n parallelograms at abc[w..], plus the residual r: exact whatever the values (each
 * within 2^52, so |S| < 2^56). In binary64 while every partial sum stays below 2^53 in magnitude
 * (then each is exact: a sum of integers whose exact value is within 2^53 is representable, and
 * one beyond it rounds to 2^53 or more), else in BigInt. A result beyond 2^52 is returned as is or
 * as ±Infinity, for the caller to refuse.
 * @param {Float64Array} values 3 per corner @param {Int32Array} abc @param {number} w
 * @param {number} n 1-4 @param {number} ax @param {number} r the residual, within 2^52
 */
export function averaged(values, abc, w, n, ax, r) {
  let S = 0;
  let exact = true;
  for (let i = 0; i < n; i++) {
    S += values[3 * abc[w + 3 * i] + ax];
    if (S >= TWO_53 || S <= -TWO_53) exact = false;
    S += values[3 * abc[w + 3 * i + 1] + ax];
    if (S >= TWO_53 || S <= -TWO_53) exact = false;
    S -= values[3 * abc[w + 3 * i + 2] + ax];
    if (S >= TWO_53 || S <= -TWO_53) exact = false;
  }
  if (exact && S < 2 ** 52 && S > -(2 ** 52)) {
    // |S + ⌊n/2⌋| < 2^52 + 2: exact; its quotient by 1, 2 or 4 is exact, by 3 corrected to the floor
    const s = S + (n >>> 1);
    let q = Math.floor(s / n);
    const rem = s - q * n;
    if (rem < 0) q--;
    else if (rem >= n) q++;
    // |q| ≤ 2^52 / n + 1 and |r| ≤ 2^52: the exact sum is within 2^53 + 1, and one beyond 2^52
    // stays beyond it however it rounds
    return q + r;
  }
  let big = 0n;
  for (let i = 0; i < n; i++) {
    big += BigInt(values[3 * abc[w + 3 * i] + ax]) + BigInt(values[3 * abc[w + 3 * i + 1] + ax]) - BigInt(values[3 * abc[w + 3 * i + 2] + ax]);
  }
  big += BigInt(n >>> 1);
  const N = BigInt(n);
  let q = big / N; // toward zero
  if (big % N !== 0n && big < 0n) q -= 1n;
  const v = q + BigInt(r);
  const limit = BigInt(MAX_COORD);
  return v > limit ? Infinity : v < -limit ? -Infinity : Number(v);
}
