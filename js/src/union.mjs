/**
 * The surfaces of cells (kind 1, spec §9.6) and trees (kind 2, §9.7): the boundary of a union of
 * convex pieces. Each piece's faces are cut where other pieces cover what lies just outside them;
 * what is left is the boundary. The pieces meet with T-junctions, which §9.4 allows (vertex and
 * triangle counts of these kinds are not normative; area, volume and extent are).
 */
import { fail, PlnError } from './errors.mjs';
import { intersectHalfSpaces, WORK_LIMIT } from './convex.mjs';
import { IN_LEAF } from './solids.mjs';

/** A polygon vertex counts as on a plane within this fraction of the group's scale. */
const ON_PLANE = 1e-10;

/** What a polygon split costs beyond its vertices, in the work budget's units (vertex visits of
 * convex clipping): its allocations take about as long as fifty such visits. */
const SPLIT_COST = 50;

/** Collects convex polygons (flat point lists) with their references; fans them at the end. */
class Surface {
  constructor() {
    /** @type {number[]} */
    this.points = [];
    /** @type {number[]} */
    this.indices = [];
    /** @type {number[]} */
    this.refs = [];
  }

  /** @param {number[]} poly @param {number} ref */
  add(poly, ref) {
    const first = this.points.length / 3;
    for (const v of poly) this.points.push(v);
    for (let i = 1; i + 1 < poly.length / 3; i++) {
      this.indices.push(first, first + i, first + i + 1);
      this.refs.push(ref);
    }
  }

  mesh() {
    return {
      positions64: new Float64Array(this.points), indices: new Uint32Array(this.indices), faceRefs: new Int32Array(this.refs),
    };
  }
}

/**
 * Splits a convex polygon by the plane (w, h) into the part with w·x ≤ h and the part with
 * w·x ≥ h (null where empty); vertices within tol of the plane go to both. `coplanar`: every
 * vertex is within tol of the plane.
 * @param {number[]} poly @param {number[]} w @param {number} h @param {number} tol
 * @param {import('./convex.mjs').Budget} budget
 * @returns {{inner: number[] | null, outer: number[] | null, coplanar: boolean}}
 */
function split(poly, w, h, tol, budget) {
  const n = poly.length / 3;
  budget.left -= n + SPLIT_COST;
  if (budget.left < 0) fail('LIMIT_EXCEEDED', `decoding work above ${WORK_LIMIT}`);
  const d = new Float64Array(n);
  let pos = false;
  let neg = false;
  for (let i = 0; i < n; i++) {
    d[i] = w[0] * poly[3 * i] + w[1] * poly[3 * i + 1] + w[2] * poly[3 * i + 2] - h;
    if (d[i] > tol) pos = true;
    else if (d[i] < -tol) neg = true;
  }
  if (!pos && !neg) return { inner: null, outer: null, coplanar: true };
  if (!pos) return { inner: poly, outer: null, coplanar: false };
  if (!neg) return { inner: null, outer: poly, coplanar: false };
  /** @type {number[]} */
  const inner = [];
  /** @type {number[]} */
  const outer = [];
  for (let i = 0; i < n; i++) {
    const j = i + 1 === n ? 0 : i + 1;
    const a = d[i];
    const b = d[j];
    if (a <= tol) inner.push(poly[3 * i], poly[3 * i + 1], poly[3 * i + 2]);
    if (a >= -tol) outer.push(poly[3 * i], poly[3 * i + 1], poly[3 * i + 2]);
    if ((a > tol && b < -tol) || (a < -tol && b > tol)) {
      const t = a / (a - b);
      for (const side of [inner, outer]) {
        for (let c = 0; c < 3; c++) side.push(poly[3 * i + c] + t * (poly[3 * j + c] - poly[3 * i + c]));
      }
    }
  }
  return { inner: inner.length >= 9 ? inner : null, outer: outer.length >= 9 ? outer : null, coplanar: false };
}

/**
 * A piece's faces as polygons: [points, outward normal, h, half-space index] per face.
 * @param {Float64Array} hs half-spaces, 4 per entry @param {number} count
 * @param {import('./convex.mjs').Budget} budget
 */
function pieceFaces(hs, count, budget) {
  const poly = intersectHalfSpaces(hs, count, budget);
  return poly.faces.map((f) => {
    /** @type {number[]} */
    const pts = [];
    for (const v of f.loop) pts.push(poly.points[3 * v], poly.points[3 * v + 1], poly.points[3 * v + 2]);
    return { pts, k: f.plane };
  });
}

/** @param {Float64Array} hs @param {number} k */
const planeOf = (hs, k) => /** @type {[number[], number]} */ ([[hs[4 * k], hs[4 * k + 1], hs[4 * k + 2]], hs[4 * k + 3]]);

/** @param {Float64Array} planes @param {number} j @param {number} s @param {Float64Array} out @param {number} k */
export function halfSpace(planes, j, s, out, k) {
  const sign = s ? -1 : 1;
  for (let c = 0; c < 4; c++) out[4 * k + c] = sign * planes[4 * j + c];
}

/** @param {Float64Array} planes 4 per reference */
function tolerance(planes) {
  let scale = 0;
  for (let i = 3; i < planes.length; i += 4) scale = Math.max(scale, Math.abs(planes[i]));
  return ON_PLANE * Math.max(scale, 1e-300);
}

/** Σ a·(b×c)/6 over a mesh's triangles. @param {{positions64: Float64Array, indices: Uint32Array}} mesh */
export function meshVolume({ positions64: p, indices: ix }) {
  let v = 0;
  for (let t = 0; t < ix.length; t += 3) {
    const a = 3 * ix[t];
    const b = 3 * ix[t + 1];
    const c = 3 * ix[t + 2];
    v += p[a] * (p[b + 1] * p[c + 2] - p[b + 2] * p[c + 1]) - p[a + 1] * (p[b] * p[c + 2] - p[b + 2] * p[c])
      + p[a + 2] * (p[b] * p[c + 1] - p[b + 1] * p[c]);
  }
  return v / 6;
}

/**
 * What of a face polygon (outward normal n) is not covered by the convex region hs: the pieces
 * of it whose points, moved a little along n, lie outside hs. Where hs has a face on the same
 * plane facing the same way, both would emit the same surface: with `yields` this face gives
 * way there (overlapping cells then show their overlap in the union's volume).
 * @param {number[]} poly @param {number[]} n @param {Float64Array} hs @param {number} count
 * @param {boolean} yields @param {number} tol @param {import('./convex.mjs').Budget} budget
 * @returns {number[][]}
 */
function uncovered(poly, n, hs, count, yields, tol, budget) {
  const left = [];
  let inside = poly;
  for (let q = 0; q < count; q++) {
    const [w, h] = planeOf(hs, q);
    const r = split(inside, w, h, tol, budget);
    if (r.coplanar) {
      // on this plane: just outside the face is inside hs only where hs lies beyond it
      if (w[0] * n[0] + w[1] * n[1] + w[2] * n[2] > 0 && !yields) return [...left, inside];
      continue;
    }
    if (r.outer && r.outer !== inside) left.push(r.outer);
    if (!r.inner) return r.outer === inside ? [...left, inside] : left;
    inside = r.inner;
  }
  return left; // what is left inside is covered
}

/**
 * Cells (§9.6): every cell bounded with an interior, interiors disjoint (the union's volume at
 * least (1 − 1e-6) × the cells' total, the reference decoder's margin), the union's boundary.
 * @param {number[][]} cells entries 2j + s @param {Float64Array} planes 4 per reference
 */
export function cellsSurface(cells, planes) {
  const budget = { left: WORK_LIMIT };
  const tol = tolerance(planes);
  const spaces = cells.map((cell) => {
    const hs = new Float64Array(4 * cell.length);
    cell.forEach((e, k) => halfSpace(planes, e >> 1, e & 1, hs, k));
    return hs;
  });
  const faces = spaces.map((hs, c) => pieceFaces(hs, cells[c].length, budget));
  const surface = new Surface();
  let total = 0;
  faces.forEach((list, c) => {
    const own = new Surface();
    for (const { pts, k } of list) {
      own.add(pts, 0);
      const [n] = planeOf(spaces[c], k);
      let pieces = [pts];
      for (let other = 0; other < cells.length && pieces.length; other++) {
        if (other === c) continue;
        const yields = other < c;
        pieces = pieces.flatMap((piece) => uncovered(piece, n, spaces[other], cells[other].length, yields, tol, budget));
      }
      for (const piece of pieces) surface.add(piece, cells[c][k] >> 1);
    }
    total += meshVolume(own.mesh());
  });
  const mesh = surface.mesh();
  if (meshVolume(mesh) < (1 - 1e-6) * total) fail('BAD_GROUP_STRUCTURE', 'cells whose interiors overlap');
  return mesh;
}

/** The most work a tree may ask (§9.7): the sum over its nodes of their depths, planefmt's limit.
 * Real trees stay far below it (js/test/hostile.test.mjs; spec §9.7 gives the corpus's figures). */
export const TREE_WORK_LIMIT = 2 ** 25;

/**
 * Trees (§9.7): the IN leaves' regions (bounded; empty ones allowed), and their faces pushed
 * down the tree from the root on their outer side: the pieces that reach an OUT leaf are the
 * boundary.
 * @param {number[]} tree tokens in version 1 numbering @param {Float64Array} planes 4 per reference
 */
export function treeSurface(tree, planes) {
  const budget = { left: WORK_LIMIT };
  const tol = tolerance(planes);
  const t = tree.length;
  const inner = new Int32Array(t).fill(-1);
  const outer = new Int32Array(t).fill(-1);
  /** @type {number[]} */
  const open = [];
  for (let i = 0; i < t; i++) {
    if (open.length) {
      const top = open[open.length - 1];
      if (inner[top] < 0) inner[top] = i;
      else {
        outer[top] = i;
        open.pop();
      }
    }
    if (tree[i] < IN_LEAF) open.push(i);
  }
  // refused before any clip: a chain of n splits asks n²/2 of them
  const depth = new Int32Array(t);
  let work = 0;
  for (let i = 0; i < t; i++) {
    work += depth[i];
    if (tree[i] < IN_LEAF) depth[inner[i]] = depth[outer[i]] = depth[i] + 1;
  }
  if (work > TREE_WORK_LIMIT) fail('LIMIT_EXCEEDED', `a tree asking ${work} clips, above ${TREE_WORK_LIMIT} (§9.7)`);
  // each node's parent and the side of its split it lies on, for the paths of the IN leaves
  const up = new Int32Array(t).fill(-1);
  for (let i = 0; i < t; i++) {
    if (tree[i] < IN_LEAF) {
      up[inner[i]] = 2 * i;
      up[outer[i]] = 2 * i + 1;
    }
  }
  const surface = new Surface();
  for (let leaf = 0; leaf < t; leaf++) {
    if (tree[leaf] !== IN_LEAF) continue;
    /** @type {number[]} the entries 2j + s of the splits above the leaf */
    const path = [];
    for (let at = up[leaf]; at >= 0; at = up[at >> 1]) path.push(2 * tree[at >> 1] + (at & 1));
    budget.left -= path.length;
    if (budget.left < 0) fail('LIMIT_EXCEEDED', `decoding work above ${WORK_LIMIT}`);
    const hs = new Float64Array(4 * path.length);
    path.forEach((e, k) => halfSpace(planes, e >> 1, e & 1, hs, k));
    let faces;
    try {
      faces = pieceFaces(hs, path.length, budget);
    } catch (err) {
      if (err instanceof PlnError && err.code === 'EMPTY_POLYTOPE') continue; // contributes nothing
      throw err;
    }
    for (const { pts, k } of faces) {
      const [n] = planeOf(hs, k);
      /** @type {[number[], number][]} */
      const work = [[pts, 0]];
      while (work.length) {
        const [poly, at] = /** @type {[number[], number]} */ (work.pop());
        const tok = tree[at];
        if (tok === IN_LEAF) continue;
        if (tok > IN_LEAF) {
          surface.add(poly, path[k] >> 1);
          continue;
        }
        const w = [planes[4 * tok], planes[4 * tok + 1], planes[4 * tok + 2]];
        const r = split(poly, w, planes[4 * tok + 3], tol, budget);
        if (r.coplanar) work.push([poly, w[0] * n[0] + w[1] * n[1] + w[2] * n[2] > 0 ? outer[at] : inner[at]]);
        else {
          if (r.inner) work.push([r.inner, inner[at]]);
          if (r.outer) work.push([r.outer, outer[at]]);
        }
      }
    }
  }
  return surface.mesh();
}
