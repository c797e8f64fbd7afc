/** Part groups GRUP: head (spec §9.1), common body (§9.2), kinds (§9.3) and their kind data. */
import { DECLARED_KINDS, NO_CHARGE } from './budget.mjs';
import { fail } from './errors.mjs';
import { Cursor, readBits } from './varint.mjs';
import { decompress } from './compression.mjs';
import { readCells, readTree } from './solids.mjs';
import { readSealed } from './sealed.mjs';
import { readShell } from './shells.mjs';
import { readShellTree } from './shelltree.mjs';
import { readShellWalk } from './shellwalk.mjs';

/**
 * @typedef {object} Group
 * @property {number} index
 * @property {number} object
 * @property {number} kind
 * @property {Uint32Array} refs plane-table indices
 * @property {Uint8Array} roles 1 where the reference's role bit is set, one byte per reference
 * @property {boolean} skipped a kind of a newer minor version (§9.3), or a copy of such a group
 *   (§9.15 step 3): no kind data read (a copy's source is read)
 * @property {any} data the kind data: cells, tree, a Shell (kinds 5-10, 12 and 13), or {source} (kind 11)
 */

/** The newest minor version this reader knows, per major (§5, §9.3): 6.0, 5.2 (kind 13), 4.2 (kinds 10, 11), 3.4 (kind 8). */
export const NEWEST_MINOR = { 1: 0, 2: 0, 3: 4, 4: 2, 5: 2, 6: 0 };

/**
 * Whether `kind` is a kind of the file's version (§9.3).
 * @param {number} kind @param {[number, number]} version
 */
function kindOfVersion(kind, [major, minor]) {
  if (kind <= 4) return true;
  if (major >= 6) return kind <= 13;
  // kinds 0-11 in 5.0, 0-12 in 5.1, 0-13 in 5.2 (and later minors); kinds 0-8 in 4.0, 0-9 in 4.1, 0-11 in 4.2 (and later minors)
  if (major >= 5) return kind <= (minor >= 2 ? 13 : minor >= 1 ? 12 : 11);
  if (major >= 4) return kind <= (minor >= 2 ? 11 : minor >= 1 ? 9 : 8);
  return major === 3 && kind <= 8 && minor >= kind - 4;
}

/**
 * @typedef {object} GroupContext
 * @property {[number, number]} version
 * @property {number} groups groups read before
 * @property {Group[]} earlier the groups read before, in file order: the sources a copy (kind 11) may name
 * @property {number} objects objects read before
 * @property {number} planes planes defined before this chunk
 * @property {import('./compression.mjs').Limits} limits
 * @property {import('./compression.mjs').Codecs} codecs
 * @property {import('./budget.mjs').Budget} [budget] charged the counts a sealed or shell group declares,
 *   and a copy of one its source's, as they are read (§12.4)
 */

/**
 * Reads one GRUP payload (versions 1 to 5).
 * @param {Uint8Array} payload
 * @param {GroupContext} ctx
 * @returns {Group}
 */
export function readGroup(payload, ctx) {
  const c = new Cursor(payload);
  const major = ctx.version[0];
  let index;
  let object;
  let kind;
  let method;
  let rawSize;
  if (major < 3) {
    if (payload.length < 16) fail('BAD_PAYLOAD', 'GRUP head under 16 bytes');
    index = c.u32();
    object = c.u32();
    kind = c.u8();
    method = c.u8();
    c.pos += 2;
    rawSize = c.u32();
  } else {
    index = c.varint32();
    object = c.varint32();
    kind = c.u8();
    method = c.u8();
    rawSize = c.varint32();
  }
  if (index !== ctx.groups) fail('GROUP_INDEX_MISMATCH', `index ${index}, expected ${ctx.groups}`);
  if (object >= ctx.objects) fail('BAD_OBJECT_REFERENCE', `object ${object} not defined`);
  const skipped = skips(kind, ctx.version);
  const body = decompress(method, rawSize, payload.subarray(c.pos), ctx.limits, ctx.codecs, major);
  return readBody(body, index, object, kind, skipped, ctx);
}

/**
 * Reads one group record of version 6: object, kind and the body, raw (its segment was decompressed).
 * @param {Uint8Array} payload
 * @param {GroupContext} ctx
 * @returns {Group}
 */
export function readGroupRecord(payload, ctx) {
  const c = new Cursor(payload);
  const object = c.varint32();
  const kind = c.u8();
  if (object >= ctx.objects) fail('BAD_OBJECT_REFERENCE', `object ${object} not defined`);
  return readBody(payload.subarray(c.pos), ctx.groups, object, kind, skips(kind, ctx.version), ctx);
}

/**
 * Whether a group of `kind` is skipped (a kind of a newer minor version, §9.3), or UNKNOWN_GROUP_KIND.
 * @param {number} kind @param {[number, number]} version
 */
function skips(kind, version) {
  if (kindOfVersion(kind, version)) return false;
  if (version[1] <= NEWEST_MINOR[/** @type {1|2|3|4|5|6} */ (version[0])]) {
    fail('UNKNOWN_GROUP_KIND', `kind ${kind} in a ${version.join('.')} file`);
  }
  return true;
}

/**
 * §9.2 onward: the common body and the kind data.
 * @param {Uint8Array} body raw @param {number} index @param {number} object @param {number} kind
 * @param {boolean} skipped @param {GroupContext} ctx
 * @returns {Group}
 */
function readBody(body, index, object, kind, skipped, ctx) {
  const major = ctx.version[0];
  const b = new Cursor(body);
  // version 5: a shell (kinds 6-10, 12 and 13) or a copy (11) may have no reference, and a kind this reader skips decides for itself (§9.2)
  const none = major >= 5 && (skipped || (kind >= 6 && kind <= 13));
  const { refs, roles } = major === 1 ? readCommonV1(b, ctx) : readCommon(b, ctx, none);
  const m = refs.length;
  let data = null;
  if (!skipped && kind === 11) {
    const copy = readCopy(b, index, refs, roles, ctx.earlier);
    skipped = copy.skipped;
    data = { source: copy.source };
    const src = ctx.earlier[copy.source];
    if (!skipped && ctx.budget && DECLARED_KINDS.has(src.kind)) ctx.budget.charge(index, src.data.V, src.data.T);
  } else if (!skipped) {
    const charge = ctx.budget ? ctx.budget.of(index) : NO_CHARGE;
    if (kind === 0 || kind === 3 || kind === 4) {
      if (b.left > 0) fail('BAD_PAYLOAD', `${b.left} bytes after the roles of a kind ${kind} group`);
    } else if (kind === 1) data = readCells(b, m, major, ctx.limits);
    else if (kind === 2) data = readTree(b, m, major);
    else if (kind === 5) data = readSealed(b, roles, charge);
    else {
      // version 5's shell grids are f32 (16 bytes), earlier ones f64 (32 bytes): §9.10, A.5
      const f32Grid = major >= 5;
      if (kind === 6) data = readShell(b, roles, f32Grid, charge);
      else if (kind === 9 || kind === 10 || kind === 12 || kind === 13) data = readShellWalk(b, roles, kind, f32Grid, charge);
      else data = readShellTree(b, roles, kind === 8, f32Grid, charge);
    }
  }
  return { index, object, kind, refs, roles, skipped, data };
}

/**
 * §9.15, a copy's kind data, with its checks in their order: the source's varint and nothing after
 * it (BAD_PAYLOAD); a source not before the copy, or itself a copy (BAD_GROUP_STRUCTURE); a skipped
 * source (the copy is skipped too); references and role bits other than the source's
 * (BAD_GROUP_STRUCTURE).
 * @param {Cursor} b at the kind data
 * @param {number} index the copy's index
 * @param {Uint32Array} refs @param {Uint8Array} roles the copy's common body
 * @param {Group[]} earlier the groups before the copy
 * @returns {{source: number, skipped: boolean}}
 */
function readCopy(b, index, refs, roles, earlier) {
  const s = b.varint();
  if (b.left > 0) fail('BAD_PAYLOAD', `${b.left} bytes after a copy's source`);
  if (s >= index) fail('BAD_GROUP_STRUCTURE', `copy ${index} of group ${s}, not an earlier group`);
  const src = earlier[s];
  if (src.kind === 11) fail('BAD_GROUP_STRUCTURE', `copy ${index} of group ${s}, itself a copy`);
  if (src.skipped) return { source: s, skipped: true };
  const m = refs.length;
  if (src.refs.length !== m) fail('BAD_GROUP_STRUCTURE', `copy ${index}: ${m} references, its source ${src.refs.length}`);
  for (let i = 0; i < m; i++) {
    if (refs[i] !== src.refs[i]) fail('BAD_GROUP_STRUCTURE', `copy ${index}: reference ${i} is ${refs[i]}, its source's ${src.refs[i]}`);
  }
  for (let i = 0; i < m; i++) {
    if (roles[i] !== src.roles[i]) fail('BAD_GROUP_STRUCTURE', `copy ${index}: role bit ${i} is ${roles[i]}, its source's ${src.roles[i]}`);
  }
  return { source: s, skipped: false };
}

/**
 * §9.2: varint references as differences, then role bits (versions 2 to 5).
 * @param {Cursor} b @param {{planes: number, limits: import('./compression.mjs').Limits}} ctx
 * @param {boolean} [none] m = 0 is allowed (version 5: shells, copies, skipped kinds)
 */
function readCommon(b, ctx, none = false) {
  const m = b.varint();
  if (m > ctx.limits.refs) fail('LIMIT_EXCEEDED', `${m} references`);
  if (m === 0 && !none) fail('BAD_GROUP_STRUCTURE', 'no reference');
  // each reference takes a byte at least: more than the bytes left is a body that ends inside them
  if (m > b.left) fail('BAD_PAYLOAD', `${m} references in ${b.left} bytes`);
  const d = new Float64Array(m);
  for (let i = 0; i < m; i++) d[i] = b.varint();
  const refs = new Uint32Array(m);
  let sum = 0;
  for (let i = 0; i < m; i++) {
    if (d[i] >= ctx.planes) fail('BAD_PLANE_REFERENCE', `difference ${d[i]}, ${ctx.planes} planes defined`);
    sum += d[i];
    if (sum >= ctx.planes) fail('BAD_PLANE_REFERENCE', `reference ${sum}, ${ctx.planes} planes defined`);
    refs[i] = sum;
  }
  return { refs, roles: readBits(b, m) };
}

/**
 * A.1: u32 references in any order.
 * @param {Cursor} b @param {{planes: number, limits: import('./compression.mjs').Limits}} ctx
 */
function readCommonV1(b, ctx) {
  const m = b.u32();
  if (m > ctx.limits.refs) fail('LIMIT_EXCEEDED', `${m} references`);
  if (b.left < 4 * m + Math.ceil(m / 8)) fail('BAD_PAYLOAD', 'body ends inside the references or roles');
  if (m === 0) fail('BAD_GROUP_STRUCTURE', 'no reference');
  const refs = new Uint32Array(m);
  for (let i = 0; i < m; i++) {
    refs[i] = b.u32();
    if (refs[i] >= ctx.planes) fail('BAD_PLANE_REFERENCE', `reference ${refs[i]}, ${ctx.planes} planes defined`);
  }
  return { refs, roles: readBits(b, m) };
}
