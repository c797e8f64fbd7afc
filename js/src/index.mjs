/**
 * planefmt's .pln files in JavaScript: read a file (spec/pln.md) and decode its geometry.
 * Browser-safe: no Node import here (Node's zlib and Brotli come in through node.mjs, the browser's
 * through browser.mjs).
 */
import { readContainer } from './reader.mjs';
import { decodeGroup } from './decode.mjs';
import { PlnError } from './errors.mjs';
import { DECLARED_KINDS } from './budget.mjs';

export { PlnError };

/**
 * @typedef {object} ReadOptions
 * @property {import('./compression.mjs').InflateFn | null} [inflate] zlib inflater for payloads of method 1 (§6)
 * @property {import('./compression.mjs').BrotliFn | null} [brotli] Brotli decompressor for payloads of method 2 (§6, version 4)
 * @property {boolean} [decode] decode geometry (default true)
 * @property {Partial<import('./compression.mjs').Limits>} [limits] resource limits (§12.4)
 */

/**
 * @typedef {object} MeshGroup
 * @property {number} kind
 * @property {number} index the group's index in the file
 * @property {number | null} source a copy's (kind 11) source group, whose surface it has (§9.15); else null
 * @property {Float32Array} positions 3 per vertex, object-local
 * @property {Float64Array} positions64 the same in binary64, as decoded
 * @property {Uint32Array} indices 3 per triangle, counter-clockwise seen from outside
 * @property {Uint8Array | null} faceColors RGBA per triangle, null without a cOLR for the group
 * @property {Int32Array} faceRefs local face reference per triangle, -1 for a free one
 */

/**
 * Reads a .pln file and, by default, decodes its geometry. Throws PlnError (`.code` of spec §12.2)
 * on an invalid file.
 * @param {ArrayBuffer | Uint8Array} input
 * @param {ReadOptions} [options]
 */
export function readPln(input, options = {}) {
  try {
    return read(input instanceof Uint8Array ? input : new Uint8Array(input), options);
  } catch (err) {
    // every allocation is bounded by the bytes present, but a large file can still need more
    // memory than the engine gives: that is a limit of this reader (§12.4), not a crash
    if (err instanceof RangeError && /allocation failed|Invalid (typed )?array length/i.test(err.message)) {
      throw new PlnError('LIMIT_EXCEEDED', `out of memory: ${err.message}`);
    }
    throw err;
  }
}

/**
 * @param {Uint8Array} bytes
 * @param {ReadOptions} options
 */
function read(bytes, options) {
  const c = readContainer(bytes, options);
  const decode = options.decode ?? true;
  /** @type {Map<number, Uint8Array>} the last cOLR of each group applies (§10.1) */
  const colourOf = new Map(c.colours.map((col) => [col.group, col.rgba]));
  /** @type {(import('./decode.mjs').GroupMesh | null)[]} the surfaces decoded so far, for copies (§9.15) */
  const surfaces = [];
  /** @type {(MeshGroup | null)[]} per group in file order; null: not decoded */
  const meshes = [];
  for (const g of c.groups) {
    const left = c.budget.limits.triangles - c.budget.triangles;
    const mesh = decode ? decodeGroup(g, c.planes, c.header, surfaces, left) : null;
    surfaces.push(mesh);
    // the reader charged the counts a sealed or shell group declares (and a copy of one): the rest here (§12.4)
    const kind = g.kind === 11 && mesh ? c.groups[g.data.source].kind : g.kind;
    if (mesh && !DECLARED_KINDS.has(kind)) c.budget.charge(g.index, mesh.positions64.length / 3, mesh.indices.length / 3);
    if (!mesh) {
      meshes.push(null);
      continue;
    }
    const source = g.kind === 11 ? g.data.source : null;
    meshes.push({
      kind: g.kind,
      index: g.index,
      source,
      // a copy shares its source's arrays
      positions: source !== null ? /** @type {MeshGroup} */ (meshes[source]).positions : new Float32Array(mesh.positions64),
      positions64: mesh.positions64,
      indices: mesh.indices,
      faceColors: colourOf.has(g.index) ? triangleColours(mesh, /** @type {Uint8Array} */ (colourOf.get(g.index))) : null,
      faceRefs: mesh.faceRefs,
    });
  }
  const objects = c.objects.map((o) => ({
    name: o.name,
    parent: o.parent,
    transform: o.transform,
    groups: /** @type {MeshGroup[]} */ (o.groups.map((g) => meshes[g.index]).filter(Boolean)),
  }));
  return {
    version: c.header.version,
    header: c.header,
    chunks: c.chunks,
    planes: c.planes,
    objects,
    /** every mETA keyword; in a version 5 file also the header's up axis, as `up_axis` (§5, §10.3) */
    metadata: metadataOf(c),
    findings: c.findings,
    /** container-level records, for validators: groups with refs, roles and kind data; cOLR chunks */
    container: c,
    /** per group in file order, null where not decoded */
    meshes,
    mesh: () => mergedMesh(objects),
  };
}

/**
 * The file's metadata as mETA says it, with a version 5 header's up axis where mETA said it before
 * (a version 5 file has no mETA up_axis: BAD_METADATA, so nothing is overwritten).
 * @param {import('./reader.mjs').Container} c
 * @returns {Record<string, string>}
 */
function metadataOf(c) {
  if (!c.header.up_axis) return c.metadata;
  const out = Object.assign(Object.create(null), c.metadata);
  out.up_axis = c.header.up_axis;
  return out;
}

/**
 * @param {{faceRefs: Int32Array, freeRef: number}} mesh @param {Uint8Array} rgba 4 per reference
 */
function triangleColours(mesh, rgba) {
  const T = mesh.faceRefs.length;
  const out = new Uint8Array(4 * T);
  for (let t = 0; t < T; t++) {
    const r = mesh.faceRefs[t] < 0 ? mesh.freeRef : mesh.faceRefs[t];
    out.set(rgba.subarray(4 * r, 4 * r + 4), 4 * t);
  }
  return out;
}

/**
 * Each object's local-to-world matrix (§8: M_root ⋯ M_parent · M), row by row; parents come first.
 * @param {{parent: number | null, transform: number[] | null}[]} objects
 */
export function worldMatrices(objects) {
  /** @type {number[][]} */
  const world = [];
  for (const o of objects) {
    const local = o.transform ?? [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];
    world.push(o.parent === null ? local : multiply(world[o.parent], local));
  }
  return world;
}

/** @param {number[]} a @param {number[]} b 4×4 row by row */
function multiply(a, b) {
  const out = new Array(16).fill(0);
  for (let i = 0; i < 4; i++) for (let j = 0; j < 4; j++) for (let k = 0; k < 4; k++) out[4 * i + j] += a[4 * i + k] * b[4 * k + j];
  return out;
}

/**
 * Every decoded group in world coordinates, as one mesh. A mirroring transform (det < 0) reverses
 * triangle winding (§8), so those triangles are flipped back to face outwards.
 * @param {{parent: number | null, transform: number[] | null, groups: MeshGroup[]}[]} objects
 */
function mergedMesh(objects) {
  const world = worldMatrices(objects);
  let nv = 0;
  let nt = 0;
  for (const o of objects) for (const g of o.groups) { nv += g.positions64.length / 3; nt += g.indices.length / 3; }
  const positions = new Float64Array(3 * nv);
  const indices = new Uint32Array(3 * nt);
  const groupOfTriangle = new Uint32Array(nt);
  let v0 = 0;
  let t0 = 0;
  objects.forEach((o, k) => {
    const M = world[k];
    const det = M[0] * (M[5] * M[10] - M[6] * M[9]) - M[1] * (M[4] * M[10] - M[6] * M[8]) + M[2] * (M[4] * M[9] - M[5] * M[8]);
    for (const g of o.groups) {
      const p = g.positions64;
      for (let i = 0; i < p.length; i += 3) {
        for (let r = 0; r < 3; r++) {
          positions[3 * v0 + i + r] = M[4 * r] * p[i] + M[4 * r + 1] * p[i + 1] + M[4 * r + 2] * p[i + 2] + M[4 * r + 3];
        }
      }
      const flip = det < 0;
      const src = g.indices;
      const at = 3 * t0;
      for (let t = 0; t < src.length; t += 3) {
        indices[at + t] = src[t] + v0;
        indices[at + t + 1] = src[flip ? t + 2 : t + 1] + v0;
        indices[at + t + 2] = src[flip ? t + 1 : t + 2] + v0;
      }
      groupOfTriangle.fill(g.index, t0, t0 + src.length / 3);
      v0 += p.length / 3;
      t0 += g.indices.length / 3;
    }
  });
  return { positions: new Float32Array(positions), positions64: positions, indices, groupOfTriangle };
}
