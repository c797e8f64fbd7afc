/** Shell groups (kind 6, spec §9.10), and the Shell structure sealed groups and shell trees share. */
import { fail } from './errors.mjs';
import { NO_CHARGE } from './budget.mjs';
import { unzigzag, readBits } from './varint.mjs';

export const MAX_COORD = 2 ** 52;

/**
 * A triangle surface over corners, as kinds 5, 6 and 7 store it once read and checked.
 * @typedef {object} Shell
 * @property {number} V corners
 * @property {number} T triangles
 * @property {Uint8Array} explicit 1 where a corner is explicit
 * @property {Int32Array} cornerPlanes 3 local references per corner (named corners; -1 for explicit ones)
 * @property {Float64Array} grid 3 integer coordinates per corner (explicit corners; 0 for named ones)
 * @property {number[] | null} origin grid origin, null without explicit corners
 * @property {number | null} step grid step, null without explicit corners
 * @property {Int32Array} face local face reference per triangle, -1 for a free triangle
 * @property {Uint32Array} tri 3 corners per triangle
 */

/**
 * Reads a varint per element of a new Float64Array, refusing counts the bytes left cannot hold
 * (each varint takes a byte at least) before allocating.
 * @param {import('./varint.mjs').Cursor} b @param {number} n
 */
export function readVarints(b, n) {
  if (n > b.left) fail('BAD_PAYLOAD', `${n} varints in ${b.left} bytes`);
  const out = new Float64Array(n);
  for (let i = 0; i < n; i++) out[i] = b.varint();
  return out;
}

/**
 * The grid of §9.10, read (origin x, y, z and step: f32 each in version 5, 16 bytes; f64 each
 * before, 32 bytes, A.5); checked by checkGrid.
 * @param {import('./varint.mjs').Cursor} b
 * @param {boolean} [f32]
 */
export function readGrid(b, f32 = false) {
  const read = f32 ? () => b.f32() : () => b.f64();
  const origin = [read(), read(), read()];
  return { origin, step: read() };
}

/** @param {{origin: number[], step: number}} g */
export function checkGrid(g) {
  if (!g.origin.every(Number.isFinite) || !(Number.isFinite(g.step) && g.step > 0)) {
    fail('BAD_GROUP_STRUCTURE', 'grid origin not finite or step not finite and positive');
  }
}

/**
 * Checks a named corner's three references: different, each < m.
 * @param {Int32Array} cp @param {number} k @param {number} m
 */
export function checkNamed(cp, k, m) {
  const a = cp[3 * k];
  const b = cp[3 * k + 1];
  const c = cp[3 * k + 2];
  if (a >= m || b >= m || c >= m) fail('BAD_GROUP_STRUCTURE', `corner ${k} names a reference past ${m}`);
  if (a === b || b === c || a === c) fail('BAD_GROUP_STRUCTURE', `corner ${k} names one reference twice`);
}

/**
 * Kind 6 data, read and checked in §9.10's order.
 * @param {import('./varint.mjs').Cursor} b
 * @param {Uint8Array} roles
 * @param {boolean} [f32Grid] version 5: the grid in f32
 * @returns {Shell}
 * @param {import('./budget.mjs').Charge} [charge] takes the declared counts once checked, before
 *   anything of their size is allocated (§12.4)
 */
export function readShell(b, roles, f32Grid = false, charge = NO_CHARGE) {
  const m = roles.length;
  const V = b.varint();
  const T = b.varint();
  const U = b.varint();
  const left = b.left;
  if (V < 3 || V > 8 * left || T < 1 || 3 * T > left || U > T) {
    fail('BAD_GROUP_STRUCTURE', `counts V=${V} T=${T} U=${U} for ${left} bytes`);
  }
  charge(V, T);
  const explicit = readBits(b, V);
  let E = 0;
  for (let k = 0; k < V; k++) E += explicit[k];
  const named = readVarints(b, 3 * (V - E));
  const grid = E > 0 ? readGrid(b, f32Grid) : null;
  const steps = readVarints(b, 3 * E);
  const faceDiffs = readVarints(b, T - U);
  const codes = readVarints(b, 3 * T);
  if (b.left > 0) fail('BAD_GROUP_STRUCTURE', `${b.left} bytes after the corner codes`);
  // 3T codes name at most 3T corners (a final n other than V): refused before V-sized arrays
  if (V > 3 * T) fail('BAD_GROUP_STRUCTURE', `${V} corners, at most ${3 * T} named`);

  const cornerPlanes = new Int32Array(3 * V).fill(-1);
  const coords = new Float64Array(3 * V);
  const pos = [0, 0, 0];
  for (let k = 0, ni = 0, ei = 0; k < V; k++) {
    if (explicit[k]) {
      for (let a = 0; a < 3; a++) {
        const s = unzigzag(steps[3 * ei + a]);
        pos[a] += s;
        if (Math.abs(s) > MAX_COORD || Math.abs(pos[a]) > MAX_COORD) fail('BAD_GROUP_STRUCTURE', 'coordinate beyond 2^52');
        coords[3 * k + a] = pos[a];
      }
      ei++;
    } else {
      for (let a = 0; a < 3; a++) cornerPlanes[3 * k + a] = Math.min(named[3 * ni + a], 2 ** 31 - 1);
      checkNamed(cornerPlanes, k, m);
      ni++;
    }
  }
  const face = new Int32Array(T).fill(-1);
  let f = 0;
  for (let j = 0; j < T - U; j++) {
    f += faceDiffs[j];
    if (f >= m || roles[f]) fail('BAD_GROUP_STRUCTURE', `face reference ${f}`);
    face[j] = f;
  }
  if (grid) checkGrid(grid);
  const tri = new Uint32Array(3 * T);
  let n = 0;
  for (let i = 0; i < 3 * T; i++) {
    const k = codes[i];
    if (k === 0) tri[i] = n++;
    else if (k > n) fail('BAD_GROUP_STRUCTURE', `corner code ${k} names a corner below 0`);
    else tri[i] = n - k;
    if (i % 3 === 2 && (tri[i] === tri[i - 1] || tri[i] === tri[i - 2] || tri[i - 1] === tri[i - 2])) {
      fail('BAD_GROUP_STRUCTURE', `triangle ${(i - 2) / 3} names one corner twice`);
    }
  }
  if (n !== V) fail('BAD_GROUP_STRUCTURE', `${n} corners used, ${V} declared`);
  return { V, T, explicit, cornerPlanes, grid: coords, origin: grid && grid.origin, step: grid && grid.step, face, tri };
}
