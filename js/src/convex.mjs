/**
 * The convex polytope of a set of half-spaces {x : ω·x ≤ h} (spec §9.5, and the polytopes of
 * patches §9.8, cells §9.6 and tree leaves §9.7), as faces with vertex loops.
 *
 * The spec prescribes no algorithm or triangulation. This one clips a box by one half-space after
 * another, which needs no interior point and no linear program: O(m · size) for m planes, fine for
 * the hundreds of planes a convex group holds (a shell is the kind for large surfaces). Each
 * vertex keeps the three planes it lies on and is recomputed from them, so clipping a huge
 * starting box costs no accuracy. A vertex within a rounding margin of a plane counts as on it,
 * so that k > 3 planes through one point (a cube corner) give one vertex (§9.4), and at the end
 * vertices are merged by §9.4's three rules within its distance (coded planes through one corner
 * no longer meet in a point), as planefmt merges them, so that both give the same counts. The
 * planes through a vertex are its triple here (exact only where no fourth plane passes through it).
 */
import { fail } from './errors.mjs';

/** A vertex counts as on a plane within this fraction of its coordinates' and h's magnitude. */
const ON_PLANE = 1e-12;
/** Vertices closer than this fraction of the polytope's diagonal are one (§9.4's MUST). */
const MERGE = 1e-9;

/**
 * How far the coding may have moved a plane (§9.4's E = angle × R + h, R the largest distance of a
 * vertex from the origin, h + hRel × the largest |h| of the group) and half the header's tolerance in model units (L); the merge
 * distance is max(1e-9 × diagonal, min(1e-2 × diagonal, L, 1000 × E)), as planefmt's.
 * @typedef {{angle: number, h: number, hRel: number, half: number}} Coding
 */
/** @type {Coding} */
export const EXACT = { angle: 0, h: 0, hRel: 0, half: Infinity };
/** The starting box: this many times the largest |h|; a vertex on it means unbounded. */
const BOX = 1e6;

/** Vertex and loop entries one group may make the clipper visit (§12.4 lets a decoder bound its
 * work): clipping costs m × the polytope's size, so a hostile group of 10^5 planes would
 * otherwise take minutes; 1e8 visits take about a second (some 6,000 planes tangent to a sphere). */
export const WORK_LIMIT = 1e8;

/** @typedef {{left: number}} Budget work left for one group, shared by its polytopes */

/**
 * @typedef {object} Polytope
 * @property {Float64Array} points 3 per vertex
 * @property {{plane: number, loop: Int32Array}[]} faces counter-clockwise seen from outside
 */

/**
 * Intersects the inner half-spaces of planes (nx, ny, nz, h), or fails with EMPTY_POLYTOPE
 * (empty or no interior) or UNBOUNDED_POLYTOPE.
 * @param {Float64Array} planes 4 per plane: ωx, ωy, ωz, h
 * @param {number} count planes
 * @param {Budget} budget decremented by the work done; LIMIT_EXCEEDED below 0
 * @param {Coding} coding for the merge distance
 * @returns {Polytope} faces name their plane by its position in `planes`
 */
export function intersectHalfSpaces(planes, count, budget, coding = EXACT) {
  let scale = 0;
  for (let i = 0; i < count; i++) scale = Math.max(scale, Math.abs(planes[4 * i + 3]));
  if (scale === 0) scale = 1;
  const margin = normalMargin(planes, count, budget);
  // every point of the solid lies within scale / margin of the origin (§9.4): a box twice that
  // keeps the rounding margins of the clips at the solid's own size
  const R = Math.min(BOX, 2 / Math.max(margin, BOUNDED_MARGIN)) * scale;
  const all = new Float64Array(4 * (count + 6));
  all.set(planes.subarray(0, 4 * count));
  for (let a = 0; a < 3; a++) {
    all[4 * (count + 2 * a) + a] = 1;
    all[4 * (count + 2 * a) + 3] = R;
    all[4 * (count + 2 * a + 1) + a] = -1;
    all[4 * (count + 2 * a + 1) + 3] = R;
  }
  const poly = new Clipper(all, count);
  for (let i = 0; i < count; i++) {
    if (poly.clip(i) === 'empty') fail('EMPTY_POLYTOPE', `nothing left inside plane ${i}`);
    budget.left -= poly.size;
    if (budget.left < 0) fail('LIMIT_EXCEEDED', `decoding work above ${WORK_LIMIT} vertex visits`);
  }
  poly.compact();
  for (let v = 0; v < poly.nv; v++) {
    for (let s = 0; s < 3; s++) if (poly.vp[3 * v + s] >= count) fail('UNBOUNDED_POLYTOPE', 'a vertex on no three of its planes');
  }
  if (margin < BOUNDED_MARGIN) fail('UNBOUNDED_POLYTOPE', `the plane normals surround no direction by ${BOUNDED_MARGIN} (§9.4)`);
  const out = poly.merged(coding, scale);
  thick(out, all);
  return out;
}

/** A polytope thinner than this fraction of its diagonal has no interior (§9.4, planefmt's THIN). */
const THIN = 1e-8;

/**
 * EMPTY_POLYTOPE unless the polytope's least extent along a face's normal exceeds THIN × its diagonal.
 * @param {Polytope} poly @param {Float64Array} P planes
 */
function thick(poly, P) {
  const used = [...new Set(poly.faces.flatMap((f) => [...f.loop]))];
  const X = poly.points;
  const lo = [Infinity, Infinity, Infinity];
  const hi = [-Infinity, -Infinity, -Infinity];
  for (const v of used) {
    for (let c = 0; c < 3; c++) {
      lo[c] = Math.min(lo[c], X[3 * v + c]);
      hi[c] = Math.max(hi[c], X[3 * v + c]);
    }
  }
  const extent = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
  let width = Infinity;
  for (const f of poly.faces) {
    const p = 4 * f.plane;
    let far = 0;
    for (const v of used) far = Math.max(far, P[p + 3] - P[p] * X[3 * v] - P[p + 1] * X[3 * v + 1] - P[p + 2] * X[3 * v + 2]);
    width = Math.min(width, far);
  }
  if (!(width > THIN * extent)) fail('EMPTY_POLYTOPE', `${width} thick across ${extent}: no interior (§9.4)`);
}

/** The least margin by which a bounded polytope's unit normals surround the origin (§9.4, planefmt's
 * BOUNDED_MARGIN): float32's angles tilt parallel planes by ~1e-7, and a cube missing a plane is
 * unbounded, not closed 10^7 away. */
const BOUNDED_MARGIN = 1e-6;

/**
 * min over unit u of max_i ω_i·u, the distance from the origin to the boundary of the hull of the
 * unit normals: 1 / the farthest vertex of {x : ω_i·x ≤ 1}, clipped from a box of half-side
 * 2 / BOUNDED_MARGIN; 0 where that polytope reaches the box.
 * @param {Float64Array} planes @param {number} count @param {Budget} budget
 */
function normalMargin(planes, count, budget) {
  const R = 2 / BOUNDED_MARGIN;
  const all = new Float64Array(4 * (count + 6));
  for (let i = 0; i < count; i++) {
    for (let c = 0; c < 3; c++) all[4 * i + c] = planes[4 * i + c];
    all[4 * i + 3] = 1;
  }
  for (let a = 0; a < 3; a++) {
    all[4 * (count + 2 * a) + a] = 1;
    all[4 * (count + 2 * a) + 3] = R;
    all[4 * (count + 2 * a + 1) + a] = -1;
    all[4 * (count + 2 * a + 1) + 3] = R;
  }
  const polar = new Clipper(all, count);
  for (let i = 0; i < count; i++) {
    polar.clip(i);
    budget.left -= polar.size;
    if (budget.left < 0) fail('LIMIT_EXCEEDED', `decoding work above ${WORK_LIMIT} vertex visits`);
  }
  polar.compact();
  let far = 0;
  for (let v = 0; v < polar.nv; v++) {
    for (let s = 0; s < 3; s++) if (polar.vp[3 * v + s] >= count) return 0;
    far = Math.max(far, Math.hypot(polar.vx[3 * v], polar.vx[3 * v + 1], polar.vx[3 * v + 2]));
  }
  return 1 / far;
}

class Clipper {
  /** @param {Float64Array} planes all planes, the box's 6 after `count` @param {number} count */
  constructor(planes, count) {
    this.planes = planes;
    /** vertices plus loop entries: the work of one clip */
    this.size = 32;
    this.nv = 8;
    this.vx = new Float64Array(48);
    this.vp = new Int32Array(48);
    this.alive = new Uint8Array(16).fill(1, 0, 8);
    this.dist = new Float64Array(16);
    this.side = new Int8Array(16);
    /** @type {{plane: number, loop: Int32Array}[]} */
    this.faces = [];
    // the box: corner (i, j, k) bit-coded, each on one plane of each axis pair
    for (let c = 0; c < 8; c++) {
      for (let a = 0; a < 3; a++) {
        const hi = (c >> a) & 1;
        const p = count + 2 * a + (hi ? 0 : 1);
        this.vx[3 * c + a] = hi ? planes[4 * p + 3] : -planes[4 * p + 3];
        this.vp[3 * c + a] = p;
      }
    }
    // faces counter-clockwise seen from outside
    const quads = [
      [0, [1, 3, 7, 5]], [1, [0, 4, 6, 2]],
      [2, [2, 6, 7, 3]], [3, [0, 1, 5, 4]],
      [4, [4, 5, 7, 6]], [5, [0, 2, 3, 1]],
    ];
    for (const [f, loop] of quads) this.faces.push({ plane: count + /** @type {number} */ (f), loop: Int32Array.from(/** @type {number[]} */ (loop)) });
  }

  /**
   * Clips by plane p: 'empty' if nothing with an interior is left, 'redundant' if it cuts nothing.
   * New vertices are appended; vertices cut away stay in the arrays, dead, until compact().
   * @param {number} p
   */
  clip(p) {
    const P = this.planes;
    const wx = P[4 * p];
    const wy = P[4 * p + 1];
    const wz = P[4 * p + 2];
    const h = P[4 * p + 3];
    const nv = this.nv;
    const { vx, alive } = this;
    if (this.dist.length < nv) {
      this.dist = new Float64Array(2 * nv);
      this.side = new Int8Array(2 * nv);
    }
    const { dist, side } = this;
    let pos = 0;
    let neg = 0;
    for (let v = 0; v < nv; v++) {
      if (!alive[v]) continue;
      const x = vx[3 * v];
      const y = vx[3 * v + 1];
      const z = vx[3 * v + 2];
      const d = wx * x + wy * y + wz * z - h;
      const tol = ON_PLANE * (Math.abs(x) + Math.abs(y) + Math.abs(z) + Math.abs(h));
      dist[v] = d;
      const s = d > tol ? 1 : d < -tol ? -1 : 0;
      side[v] = s;
      if (s > 0) pos++;
      else if (s < 0) neg++;
    }
    if (pos === 0) return 'redundant';
    if (neg === 0) return 'empty';

    // new vertices on cut edges, shared by the two faces of each edge
    /** @type {Map<number, number>} */
    const onEdge = new Map();
    const makeVertex = (/** @type {number} */ a, /** @type {number} */ b, /** @type {number} */ facePlane) => {
      const key = a < b ? a * nv + b : b * nv + a;
      const known = onEdge.get(key);
      if (known !== undefined) {
        this.vp[3 * known + 1] = facePlane;
        return known;
      }
      const t = dist[a] / (dist[a] - dist[b]);
      const id = this.addVertex();
      const X = this.vx;
      for (let c = 0; c < 3; c++) X[3 * id + c] = X[3 * a + c] + t * (X[3 * b + c] - X[3 * a + c]);
      this.vp[3 * id] = facePlane;
      this.vp[3 * id + 1] = -1;
      this.vp[3 * id + 2] = p;
      onEdge.set(key, id);
      return id;
    };
    /** @type {Map<number, number>} directed edges of the new face, from → to */
    const cut = new Map();
    const onPlane = (/** @type {number} */ v) => v >= nv || side[v] === 0;
    const kept = [];
    let entries = 0;
    for (const face of this.faces) {
      const loop = face.loop;
      const k = loop.length;
      let anyPos = false;
      let anyOn = false;
      for (let i = 0; i < k; i++) {
        const s = side[loop[i]];
        if (s > 0) anyPos = true;
        else if (s === 0) anyOn = true;
      }
      let out = loop;
      if (anyPos) {
        const list = [];
        for (let i = 0; i < k; i++) {
          const a = loop[i];
          const b = loop[i + 1 === k ? 0 : i + 1];
          if (side[a] <= 0) list.push(a);
          if (side[a] * side[b] < 0) list.push(makeVertex(a, b, face.plane));
        }
        if (list.length < 3) continue;
        out = new Int32Array(list);
      }
      if (anyPos || anyOn) {
        const n = out.length;
        for (let i = 0; i < n; i++) {
          const u = out[i];
          const w = out[i + 1 === n ? 0 : i + 1];
          if (!onPlane(u) || !onPlane(w)) continue;
          // the face's edge u→w on the plane is w→u in the new face; one seen both ways is interior
          if (cut.get(u) === w) cut.delete(u);
          else cut.set(w, u);
        }
      }
      face.loop = out;
      kept.push(face);
      entries += out.length;
    }
    // the new face: the cut edges chained into one loop
    if (cut.size >= 3) {
      const start = /** @type {number} */ (cut.keys().next().value);
      const loop = [start];
      for (let v = cut.get(start); v !== start; v = cut.get(v)) {
        if (v === undefined || loop.length > cut.size) return this.undo(nv);
        loop.push(v);
      }
      if (loop.length !== cut.size) return this.undo(nv);
      kept.push({ plane: p, loop: new Int32Array(loop) });
      entries += loop.length;
    }
    this.faces = kept;
    let live = 0;
    for (let v = 0; v < nv; v++) {
      if (alive[v] && side[v] > 0) alive[v] = 0;
      live += alive[v];
    }
    // new vertices from their three planes where the two faces of their edge are known
    for (let v = nv; v < this.nv; v++) {
      const vp = this.vp;
      if (vp[3 * v + 1] < 0) vp[3 * v + 1] = vp[3 * v]; // an edge seen by one face only: keep the estimate
      else solveInto(P, vp[3 * v], vp[3 * v + 1], vp[3 * v + 2], this.vx, 3 * v);
      live++;
    }
    this.size = live + entries;
    if (this.nv > 2 * live + 64) this.compact();
    return 'cut';
  }

  /** Drops the vertices a clip added, for a clip given up. @param {number} nv @returns {'redundant'} */
  undo(nv) {
    this.nv = nv;
    return 'redundant';
  }

  /** @returns {number} a new vertex's index, the arrays grown as needed */
  addVertex() {
    if (3 * (this.nv + 1) > this.vx.length) {
      const cap = 2 * this.vx.length;
      const vx = new Float64Array(cap);
      vx.set(this.vx);
      const vp = new Int32Array(cap);
      vp.set(this.vp);
      const alive = new Uint8Array(cap / 3);
      alive.set(this.alive);
      [this.vx, this.vp, this.alive] = [vx, vp, alive];
    }
    this.alive[this.nv] = 1;
    return this.nv++;
  }

  /** Renumbers the vertices the faces use, dropping the others. */
  compact() {
    const remap = new Int32Array(this.nv).fill(-1);
    let count = 0;
    for (const f of this.faces) for (const v of f.loop) if (remap[v] < 0) remap[v] = count++;
    const cap = Math.max(24, 6 * count);
    const vx = new Float64Array(cap);
    const vp = new Int32Array(cap);
    for (let v = 0; v < this.nv; v++) {
      const r = remap[v];
      if (r < 0) continue;
      for (let c = 0; c < 3; c++) {
        vx[3 * r + c] = this.vx[3 * v + c];
        vp[3 * r + c] = this.vp[3 * v + c];
      }
    }
    for (const f of this.faces) for (let i = 0; i < f.loop.length; i++) f.loop[i] = remap[f.loop[i]];
    this.alive = new Uint8Array(cap / 3).fill(1, 0, count);
    [this.vx, this.vp, this.nv] = [vx, vp, count];
  }

  /**
   * The faces, with vertices joined by §9.4's merge rules (planefmt's `_merge_vertices`).
   * @param {Coding} coding
   * @param {number} scale the largest |h|
   * @returns {Polytope}
   */
  merged(coding, scale) {
    const { vx, vp, nv, planes: P } = this;
    const lo = [Infinity, Infinity, Infinity];
    const hi = [-Infinity, -Infinity, -Infinity];
    for (let v = 0; v < nv; v++) {
      for (let c = 0; c < 3; c++) {
        lo[c] = Math.min(lo[c], vx[3 * v + c]);
        hi[c] = Math.max(hi[c], vx[3 * v + c]);
      }
    }
    const D = Math.hypot(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]);
    // a turned normal moves the plane at a vertex by the angle × the vertex's distance from the origin
    let radius = 0;
    for (let v = 0; v < nv; v++) radius = Math.max(radius, Math.hypot(vx[3 * v], vx[3 * v + 1], vx[3 * v + 2]));
    const E = coding.angle * radius + coding.h + coding.hRel * scale;
    const tol = Math.max(MERGE * D, Math.min(1e-2 * D, coding.half, 1000 * E));
    /** @type {number[]} edge ends, two per edge of a face loop */
    const ends = [];
    for (const f of this.faces) {
      const n = f.loop.length;
      for (let i = 0; i < n; i++) {
        const a = f.loop[i];
        const b = f.loop[(i + 1) % n];
        if (a < b) ends.push(a, b);
      }
    }
    const m = ends.length / 2;
    const reliable = new Uint8Array(nv);
    for (let v = 0; v < nv; v++) reliable[v] = Math.abs(tripleDet(P, vp, v)) >= RELIABLE_DET ? 1 : 0;
    // the largest distance of point u from the planes of v's triple
    const off = (/** @type {number} */ u, /** @type {number} */ v) => {
      let worst = 0;
      for (let s = 0; s < 3; s++) {
        const p = vp[3 * v + s];
        worst = Math.max(worst, Math.abs(P[4 * p + 3] - P[4 * p] * vx[3 * u] - P[4 * p + 1] * vx[3 * u + 1]
          - P[4 * p + 2] * vx[3 * u + 2]));
      }
      return worst;
    };
    const edges = new Uint8Array(m);
    for (let e = 0; e < m; e++) {
      const a = ends[2 * e];
      const b = ends[2 * e + 1];
      const dx = vx[3 * a] - vx[3 * b];
      const dy = vx[3 * a + 1] - vx[3 * b + 1];
      const dz = vx[3 * a + 2] - vx[3 * b + 2];
      edges[e] = Math.hypot(dx, dy, dz) <= tol ? 1 : 0;
    }
    let label = components(nv, ends, edges);
    // two more rules, each only where the earlier ones left the ends apart: a well-conditioned
    // end within tol of the other end's planes; then two ill-conditioned ends
    const rules = [
      (/** @type {number} */ a, /** @type {number} */ b) => (reliable[a] === 1 && off(a, b) <= tol)
        || (reliable[b] === 1 && off(b, a) <= tol),
      (/** @type {number} */ a, /** @type {number} */ b) => reliable[a] === 0 && reliable[b] === 0,
    ];
    for (const rule of rules) {
      let extra = false;
      for (let e = 0; e < m; e++) {
        if (!edges[e] && rule(ends[2 * e], ends[2 * e + 1])) extra = edges[e] = 1;
      }
      if (extra) label = accept(P, vp, vx, reliable, components(nv, ends, edges), label, tol);
    }
    /** @type {Map<number, number[]>} the vertices of each label */
    const groups = new Map();
    for (let v = 0; v < nv; v++) {
      const g = groups.get(label[v]);
      if (g) g.push(v);
      else groups.set(label[v], [v]);
    }
    const points = vx.slice();
    /** the vertex standing for each label: its first member */
    const root = new Int32Array(nv);
    for (const members of groups.values()) {
      for (const v of members) root[v] = members[0];
      if (members.length > 1) weld(P, vp, members, vx, points, 3 * members[0], reliable);
    }
    const faces = [];
    for (const f of this.faces) {
      /** @type {number[]} */
      const loop = [];
      for (const v of f.loop) {
        const r = root[v];
        if (loop[loop.length - 1] !== r) loop.push(r);
      }
      while (loop.length > 1 && loop[0] === loop[loop.length - 1]) loop.pop();
      if (loop.length >= 3) faces.push({ plane: f.plane, loop: new Int32Array(loop) });
    }
    return { points, faces };
  }
}

/** A triple of unit normals spanning less volume than this pins its point too loosely for the
 * point to join a neighbour by the second rule (planefmt's RELIABLE_DET). */
const RELIABLE_DET = 1e-9;

/** @param {Float64Array} P @param {Int32Array} vp @param {number} v @returns {number} */
function tripleDet(P, vp, v) {
  const [a, b, c] = [4 * vp[3 * v], 4 * vp[3 * v + 1], 4 * vp[3 * v + 2]];
  return P[a] * (P[b + 1] * P[c + 2] - P[b + 2] * P[c + 1]) - P[a + 1] * (P[b] * P[c + 2] - P[b + 2] * P[c])
    + P[a + 2] * (P[b] * P[c + 1] - P[b + 1] * P[c]);
}

/**
 * Connected components of the vertices over the edges switched on.
 * @param {number} n @param {number[]} ends @param {Uint8Array} on
 * @returns {Int32Array} the smallest vertex of each vertex's component
 */
function components(n, ends, on) {
  const parent = new Int32Array(n);
  for (let v = 0; v < n; v++) parent[v] = v;
  const root = (/** @type {number} */ v) => {
    while (parent[v] !== v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (let e = 0; e < on.length; e++) {
    if (!on[e]) continue;
    const a = root(ends[2 * e]);
    const b = root(ends[2 * e + 1]);
    if (a !== b) parent[Math.max(a, b)] = Math.min(a, b);
  }
  const out = new Int32Array(n);
  for (let v = 0; v < n; v++) out[v] = root(v);
  return out;
}

/**
 * The joined labels where a group they join has planes that pin one point within tol (the smallest
 * eigenvalue of Σ ωωᵀ at least 1e-6 of the largest, the least-squares point within tol of each),
 * the previous labels elsewhere (§9.4).
 * @param {Float64Array} P @param {Int32Array} vp @param {Float64Array} vx @param {Uint8Array} reliable
 * @param {Int32Array} joined @param {Int32Array} previous @param {number} tol
 * @returns {Int32Array} labels: a vertex index per vertex
 */
function accept(P, vp, vx, reliable, joined, previous, tol) {
  const n = joined.length;
  /** @type {Map<number, number[]>} */
  const groups = new Map();
  for (let v = 0; v < n; v++) {
    const g = groups.get(joined[v]);
    if (g) g.push(v);
    else groups.set(joined[v], [v]);
  }
  // a group accepted or unchanged keeps its joined label, the others their previous ones (n apart)
  const key = Int32Array.from(previous, (p) => n + p);
  for (const members of groups.values()) {
    const same = members.every((v) => previous[v] === previous[members[0]]);
    if (same || pins(P, vp, vx, reliable, members, tol)) for (const v of members) key[v] = joined[v];
  }
  /** @type {Map<number, number>} */
  const first = new Map();
  return key.map((k, v) => {
    if (!first.has(k)) first.set(k, v);
    return /** @type {number} */ (first.get(k));
  });
}

/**
 * Whether the planes of the members' triples pin one point within tol of each of them.
 * @param {Float64Array} P @param {Int32Array} vp @param {Float64Array} vx @param {Uint8Array} reliable
 * @param {number[]} members @param {number} tol
 */
function pins(P, vp, vx, reliable, members, tol) {
  const planes = new Set();
  for (const v of members) for (let s = 0; s < 3; s++) planes.add(vp[3 * v + s]);
  const A = new Float64Array(9);
  for (const p of planes) {
    for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++) A[3 * i + j] += P[4 * p + i] * P[4 * p + j];
  }
  const [small, large] = eigenRange(A);
  if (!(small >= 1e-6 * large)) return false;
  const x = new Float64Array(3);
  weld(P, vp, members, vx, x, 0, reliable);
  for (const p of planes) {
    if (!(Math.abs(P[4 * p + 3] - P[4 * p] * x[0] - P[4 * p + 1] * x[1] - P[4 * p + 2] * x[2]) <= tol)) return false;
  }
  return true;
}

/**
 * The smallest and largest eigenvalues of a symmetric 3×3 matrix (the trigonometric solution).
 * @param {Float64Array} A @returns {[number, number]}
 */
function eigenRange(A) {
  const p1 = A[1] * A[1] + A[2] * A[2] + A[5] * A[5];
  const q = (A[0] + A[4] + A[8]) / 3;
  if (p1 === 0) return [Math.min(A[0], A[4], A[8]), Math.max(A[0], A[4], A[8])];
  const p2 = (A[0] - q) ** 2 + (A[4] - q) ** 2 + (A[8] - q) ** 2 + 2 * p1;
  const p = Math.sqrt(p2 / 6);
  const B = A.map((a, i) => (a - (i % 4 === 0 ? q : 0)) / p);
  const detB = B[0] * (B[4] * B[8] - B[5] * B[7]) - B[1] * (B[3] * B[8] - B[5] * B[6]) + B[2] * (B[3] * B[7] - B[4] * B[6]);
  const phi = Math.acos(Math.min(1, Math.max(-1, detB / 2))) / 3;
  const large = q + 2 * p * Math.cos(phi);
  const small = q + 2 * p * Math.cos(phi + (2 * Math.PI) / 3);
  return [small, large];
}

/**
 * The least-squares point of the distinct planes of members' triples, into out[at..at+2]: one
 * Gauss-Newton step from the mean of the members (of the well-conditioned ones where there are
 * any), the mean itself where the normal equations are singular (planefmt's resolve_vertices).
 * @param {Float64Array} P planes @param {Int32Array} vp triples @param {number[]} members
 * @param {Float64Array} vx points @param {Float64Array} out @param {number} at
 * @param {Uint8Array} [reliable] well-conditioned vertices
 */
function weld(P, vp, members, vx, out, at, reliable) {
  const some = reliable !== undefined && members.some((v) => reliable[v] === 1);
  const from = some ? members.filter((v) => /** @type {Uint8Array} */ (reliable)[v] === 1) : members;
  const start = [0, 0, 0];
  for (const v of from) for (let k = 0; k < 3; k++) start[k] += vx[3 * v + k] / from.length;
  const planes = new Set();
  for (const v of members) for (let s = 0; s < 3; s++) planes.add(vp[3 * v + s]);
  const A = new Float64Array(9);
  const b = new Float64Array(3);
  for (const p of planes) {
    const r = P[4 * p + 3] - P[4 * p] * start[0] - P[4 * p + 1] * start[1] - P[4 * p + 2] * start[2];
    for (let i = 0; i < 3; i++) {
      b[i] += P[4 * p + i] * r;
      for (let j = 0; j < 3; j++) A[3 * i + j] += P[4 * p + i] * P[4 * p + j];
    }
  }
  const det3 = (/** @type {Float64Array} */ m) => m[0] * (m[4] * m[8] - m[5] * m[7]) - m[1] * (m[3] * m[8] - m[5] * m[6])
    + m[2] * (m[3] * m[7] - m[4] * m[6]);
  const det = det3(A);
  for (let k = 0; k < 3; k++) {
    if (!(det > 1e-12)) {
      out[at + k] = start[k];
      continue;
    }
    const Ak = A.slice();
    for (let i = 0; i < 3; i++) Ak[3 * i + k] = b[i];
    out[at + k] = start[k] + det3(Ak) / det;
  }
}

/**
 * Where planes a, b, c meet, by Cramer's rule, written to out[at..at+2] unless the normals are
 * nearly dependent (then out keeps its estimate).
 * @param {Float64Array} P @param {number} a @param {number} b @param {number} c
 * @param {Float64Array} out @param {number} at
 */
function solveInto(P, a, b, c, out, at) {
  const [ax, ay, az, ah] = [P[4 * a], P[4 * a + 1], P[4 * a + 2], P[4 * a + 3]];
  const [bx, by, bz, bh] = [P[4 * b], P[4 * b + 1], P[4 * b + 2], P[4 * b + 3]];
  const [cx, cy, cz, ch] = [P[4 * c], P[4 * c + 1], P[4 * c + 2], P[4 * c + 3]];
  const det = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx);
  if (!(Math.abs(det) > 1e-9)) return;
  out[at] = (ah * (by * cz - bz * cy) - ay * (bh * cz - bz * ch) + az * (bh * cy - by * ch)) / det;
  out[at + 1] = (ax * (bh * cz - bz * ch) - ah * (bx * cz - bz * cx) + az * (bx * ch - bh * cx)) / det;
  out[at + 2] = (ax * (by * ch - bh * cy) - ay * (bx * ch - bh * cx) + ah * (bx * cy - by * cx)) / det;
}
