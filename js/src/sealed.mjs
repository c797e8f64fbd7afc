/** Sealed groups (kind 5, spec §9.9), read into the Shell structure of shells.mjs. */
import { fail } from './errors.mjs';
import { NO_CHARGE } from './budget.mjs';
import { readVarints, checkNamed } from './shells.mjs';

/**
 * @param {import('./varint.mjs').Cursor} b
 * @param {Uint8Array} roles
 * @returns {import('./shells.mjs').Shell}
 * @param {import('./budget.mjs').Charge} [charge] takes the declared counts once checked, before
 *   anything of their size is allocated (§12.4)
 */
export function readSealed(b, roles, charge = NO_CHARGE) {
  const m = roles.length;
  const V = b.varint();
  if (V < 3 || 3 * V > b.left) fail('BAD_GROUP_STRUCTURE', `vertex count ${V} for ${b.left} bytes`);
  charge(V, 0);
  const named = readVarints(b, 3 * V);
  const T = b.varint();
  if (T < 1 || 4 * T > b.left) fail('BAD_GROUP_STRUCTURE', `triangle count ${T} for ${b.left} bytes`);
  charge(0, T);
  const tris = readVarints(b, 4 * T);
  if (b.left > 0) fail('BAD_GROUP_STRUCTURE', `${b.left} bytes after the triangles`);

  const cornerPlanes = new Int32Array(3 * V);
  for (let i = 0; i < 3 * V; i++) cornerPlanes[i] = Math.min(named[i], 2 ** 31 - 1);
  for (let k = 0; k < V; k++) checkNamed(cornerPlanes, k, m);
  const face = new Int32Array(T);
  const tri = new Uint32Array(3 * T);
  const used = new Uint8Array(V);
  let f = 0;
  for (let j = 0; j < T; j++) {
    f += tris[4 * j];
    if (f >= m || roles[f]) fail('BAD_GROUP_STRUCTURE', `face reference ${f}`);
    face[j] = f;
    const [i0, i1, i2] = [tris[4 * j + 1], tris[4 * j + 2], tris[4 * j + 3]];
    if (i0 >= V || i1 >= V || i2 >= V) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names a vertex past ${V}`);
    if (i0 === i1 || i1 === i2 || i0 === i2) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names one vertex twice`);
    tri[3 * j] = i0;
    tri[3 * j + 1] = i1;
    tri[3 * j + 2] = i2;
    used[i0] = used[i1] = used[i2] = 1;
  }
  if (used.includes(0)) fail('BAD_GROUP_STRUCTURE', 'a vertex on no triangle');
  return {
    V, T, explicit: new Uint8Array(V), cornerPlanes, grid: new Float64Array(3 * V), origin: null, step: null, face, tri,
  };
}
