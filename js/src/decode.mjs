/** Geometry of part groups (spec §9.4-§9.16): each group to an indexed triangle mesh. */
import { fail } from './errors.mjs';
import { intersectHalfSpaces, WORK_LIMIT, EXACT } from './convex.mjs';
import { cellsSurface, treeSurface, halfSpace } from './union.mjs';

/**
 * @typedef {object} GroupMesh
 * @property {number} kind the group's kind (11 for a copy, whose other fields are its source's)
 * @property {Float64Array} positions64 3 per vertex, object-local
 * @property {Uint32Array} indices 3 per triangle, counter-clockwise seen from outside
 * @property {Int32Array} faceRefs local face reference per triangle, -1 for a free triangle
 * @property {number} freeRef the reference whose colour free triangles take (the last)
 */

/**
 * ω and h of each reference, in binary64 from the stored triplets (§2.3, §9.4).
 * @param {import('./groups.mjs').Group} group @param {Float64Array} table
 */
function planesOf(group, table) {
  const m = group.refs.length;
  const out = new Float64Array(4 * m);
  for (let i = 0; i < m; i++) {
    const r = 3 * group.refs[i];
    const nu = table[r];
    const phi = table[r + 1];
    out[4 * i] = Math.sin(nu) * Math.cos(phi);
    out[4 * i + 1] = Math.sin(nu) * Math.sin(phi);
    out[4 * i + 2] = Math.cos(nu);
    out[4 * i + 3] = table[r + 2];
  }
  return out;
}

/**
 * The decoded surface of a group, or null for a skipped kind.
 * @param {import('./groups.mjs').Group} group
 * @param {Float64Array} table the plane table
 * @param {import('./header.mjs').Header} header for the merge distance of polytopes (§9.4)
 * @param {(GroupMesh | null)[]} [earlier] the surfaces of the groups before it, for a copy (kind 11)
 * @param {number} [trianglesLeft] what the decode budget leaves (§12.4): a patch that repeats a face
 *   reference, whose output outgrows its body, stops at it before making its triangles
 * @returns {GroupMesh | null}
 */
export function decodeGroup(group, table, header, earlier = [], trianglesLeft = Infinity) {
  if (group.skipped) return null;
  if (group.kind === 11) {
    // §9.15: the source's surface (its references are the copy's), in the copy's object; the
    // arrays are shared, not copied
    const src = earlier[group.data.source];
    if (!src) throw new Error(`copy ${group.index}: its source ${group.data.source} is not decoded`);
    return { ...src, kind: 11 };
  }
  const planes = planesOf(group, table);
  const m = group.refs.length;
  /** @type {import('./convex.mjs').Budget} */
  const budget = { left: WORK_LIMIT };
  const coding = codingError(header);
  // free triangles take the last reference's colour; a group without references its cOLR's one (§10.1)
  const base = { kind: group.kind, freeRef: Math.max(m - 1, 0) };
  switch (group.kind) {
    case 0:
      return { ...base, ...polytopeFaces(group, planes, null, budget, coding, Infinity) };
    case 3:
    case 4: {
      const faceRefs = [];
      for (let i = 0; i < m; i++) if (!group.roles[i]) faceRefs.push(i);
      const mesh = polytopeFaces(group, planes, faceRefs, budget, coding, trianglesLeft);
      if (mesh.indices.length === 0) fail('EMPTY_POLYTOPE', 'no face on a face plane');
      if (group.kind === 4) {
        const ix = mesh.indices;
        for (let t = 0; t < ix.length; t += 3) [ix[t + 1], ix[t + 2]] = [ix[t + 2], ix[t + 1]];
      }
      return { ...base, ...mesh };
    }
    case 1:
      return { ...base, ...cellsSurface(group.data.cells, planes) };
    case 2:
      return { ...base, ...treeSurface(group.data.tree, planes) };
    default:
      return { ...base, ...decodeShell(group.data, planes) };
  }
}

/**
 * §9.4's E and L from the header: the larger half step of ν and φ and half the h step (codings
 * 2, 3), 2^-22 rad and 2^-24 × the largest |h| (coding 0), nothing (coding 1); half the tolerance
 * times the bbox diagonal.
 * @param {import('./header.mjs').Header} header
 * @returns {import('./convex.mjs').Coding}
 */
function codingError(header) {
  const { coding, bits, h_range: [h0, h1], bbox, tolerance } = header;
  const half = bbox && Number.isFinite(tolerance)
    ? (tolerance / 2) * Math.hypot(bbox[1][0] - bbox[0][0], bbox[1][1] - bbox[0][1], bbox[1][2] - bbox[0][2]) : Infinity;
  if (coding >= 2) {
    const angle = Math.max(Math.PI / 2 ** bits[0], Math.PI / 2 ** bits[1]);
    return { angle, h: (h1 - h0) / (2 * (2 ** bits[2] - 1)), hRel: 0, half };
  }
  // half an f32 ulp of φ in [4, 2π), the largest angle stored
  if (coding === 0) return { angle: 2 ** -22, h: 0, hRel: 2 ** -24, half };
  return { ...EXACT, half };
}

/**
 * The faces of a convex polytope, fanned into triangles.
 * @param {import('./groups.mjs').Group} group
 * @param {Float64Array} planes of the references
 * @param {number[] | null} emit null: every face (kind 0); else the face references whose faces
 *   are emitted, in order, once per reference (patches, §9.8)
 * @param {import('./convex.mjs').Budget} budget
 * @param {import('./convex.mjs').Coding} coding
 * @param {number} trianglesLeft LIMIT_EXCEEDED before making more triangles: k repeats of a face of
 *   n sides are k (n - 2) triangles from a body of k + n references
 */
function polytopeFaces(group, planes, emit, budget, coding, trianglesLeft) {
  const m = group.refs.length;
  // a repeated reference adds no plane: the polytope is built from each plane's first reference
  const firstRef = new Map();
  const unique = [];
  for (let i = 0; i < m; i++) {
    if (!firstRef.has(group.refs[i])) {
      firstRef.set(group.refs[i], i);
      unique.push(i);
    }
  }
  const hs = new Float64Array(4 * unique.length);
  unique.forEach((i, k) => halfSpace(planes, i, 0, hs, k));
  const poly = intersectHalfSpaces(hs, unique.length, budget, coding);
  /** @type {Map<number, Int32Array>} local reference → its face's loop */
  const loops = new Map();
  for (const f of poly.faces) loops.set(unique[f.plane], f.loop);
  const order = emit ? emit.map((i) => firstRef.get(group.refs[i])) : [...loops.keys()].sort((a, b) => a - b);
  const refOf = emit ?? order;
  let total = 0;
  for (const owner of order) total += Math.max((loops.get(owner)?.length ?? 2) - 2, 0);
  if (total > trianglesLeft) {
    fail('LIMIT_EXCEEDED', `group ${group.index}: its repeated face references make ${total} triangles, above the `
      + `${trianglesLeft} this reader's limit leaves (raise it with the option limits: {triangles: N}, or --max-triangles N)`);
  }
  const remap = new Map();
  /** @type {number[]} */
  const idx = [];
  /** @type {number[]} */
  const refs = [];
  order.forEach((owner, n) => {
    const loop = loops.get(owner);
    if (!loop) return;
    for (const v of loop) if (!remap.has(v)) remap.set(v, remap.size);
    for (let i = 1; i + 1 < loop.length; i++) {
      idx.push(remap.get(loop[0]), remap.get(loop[i]), remap.get(loop[i + 1]));
      refs.push(refOf[n]);
    }
  });
  const positions64 = new Float64Array(3 * remap.size);
  for (const [v, r] of remap) positions64.set(poly.points.subarray(3 * v, 3 * v + 3), 3 * r);
  return { positions64, indices: new Uint32Array(idx), faceRefs: new Int32Array(refs) };
}

/**
 * Corners and triangles of a sealed group, shell, shell tree or shell walk (§9.9-§9.13). A named corner is
 * where its three planes meet (BAD_VERTEX where their normals are nearly dependent), an explicit
 * one origin + step × its integer coordinates.
 * @param {import('./shells.mjs').Shell} shell @param {Float64Array} planes
 */
function decodeShell(shell, planes) {
  const { V, explicit, cornerPlanes: cp, grid } = shell;
  const pos = new Float64Array(3 * V);
  const [ox, oy, oz] = shell.origin ?? [0, 0, 0];
  const step = shell.step ?? 0;
  for (let k = 0; k < V; k++) {
    if (explicit[k]) {
      pos[3 * k] = ox + step * grid[3 * k];
      pos[3 * k + 1] = oy + step * grid[3 * k + 1];
      pos[3 * k + 2] = oz + step * grid[3 * k + 2];
    } else {
      const a = 4 * cp[3 * k];
      const b = 4 * cp[3 * k + 1];
      const c = 4 * cp[3 * k + 2];
      const ax = planes[a], ay = planes[a + 1], az = planes[a + 2], ah = planes[a + 3];
      const bx = planes[b], by = planes[b + 1], bz = planes[b + 2], bh = planes[b + 3];
      const cx = planes[c], cy = planes[c + 1], cz = planes[c + 2], ch = planes[c + 3];
      const m0 = by * cz - bz * cy;
      const m1 = bx * cz - bz * cx;
      const m2 = bx * cy - by * cx;
      const det = ax * m0 - ay * m1 + az * m2;
      if (!(Math.abs(det) > 1e-12)) fail('BAD_VERTEX', `corner ${k}: |det| ${Math.abs(det)}`);
      pos[3 * k] = (ah * m0 - ay * (bh * cz - bz * ch) + az * (bh * cy - by * ch)) / det;
      pos[3 * k + 1] = (ax * (bh * cz - bz * ch) - ah * m1 + az * (bx * ch - bh * cx)) / det;
      pos[3 * k + 2] = (ax * (by * ch - bh * cy) - ay * (bx * ch - bh * cx) + ah * m2) / det;
    }
    if (!Number.isFinite(pos[3 * k]) || !Number.isFinite(pos[3 * k + 1]) || !Number.isFinite(pos[3 * k + 2])) {
      fail('BAD_VERTEX', `corner ${k} not finite`);
    }
  }
  return { positions64: pos, indices: shell.tri, faceRefs: shell.face };
}
