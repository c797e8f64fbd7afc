/** Kind data of cells (kind 1, spec §9.6) and trees (kind 2, §9.7), and A.1's version 1 forms. */
import { fail } from './errors.mjs';

/** Version 1 token values (A.1), also the runner's numbering of any version's tokens. */
export const IN_LEAF = 0xfffffffe;
const OUT_LEAF = 0xffffffff;

/**
 * @param {import('./varint.mjs').Cursor} b
 * @param {number} m references
 * @param {number} major
 * @param {import('./compression.mjs').Limits} limits
 * @returns {{cells: number[][]}} each cell's entries 2j + s
 */
export function readCells(b, m, major, limits) {
  const start = b.pos;
  const read = major === 1 ? () => b.u32() : () => b.varint();
  const c = read();
  if (major === 1) {
    if (4 * c > b.left) fail('BAD_PAYLOAD', `${c} cell sizes in ${b.left} bytes`);
  } else if (c > b.left || c > limits.refs) fail('BAD_GROUP_STRUCTURE', `cell count ${c}`);
  const sizes = [];
  for (let k = 0; k < c; k++) sizes.push(read());
  if (c === 0 || sizes.includes(0)) fail('BAD_GROUP_STRUCTURE', 'no cell, or an empty cell');
  const total = sizes.reduce((a, s) => a + s, 0);
  if (major === 1) {
    if (b.left !== 4 * total) fail('BAD_GROUP_STRUCTURE', `entries of ${b.left} bytes for ${total} entries`);
  } else if (sizes.some((s) => s > b.end - start) || total > b.left) {
    fail('BAD_GROUP_STRUCTURE', `${total} entries in ${b.left} bytes`);
  }
  const cells = sizes.map((s) => {
    const cell = [];
    for (let i = 0; i < s; i++) cell.push(read());
    return cell;
  });
  if (b.left > 0) fail('BAD_GROUP_STRUCTURE', `${b.left} bytes after the entries`);
  for (const cell of cells) for (const e of cell) if (Math.floor(e / 2) >= m) fail('BAD_GROUP_STRUCTURE', `entry ${e}`);
  return { cells };
}

/**
 * @param {import('./varint.mjs').Cursor} b
 * @param {number} m references
 * @param {number} major
 * @returns {{tree: number[]}} tokens in version 1 numbering
 */
export function readTree(b, m, major) {
  const tree = [];
  if (major === 1) {
    const t = b.u32();
    if (4 * t > b.left) fail('BAD_PAYLOAD', `${t} tokens in ${b.left} bytes`);
    for (let i = 0; i < t; i++) tree.push(b.u32());
    if (b.left > 0) fail('BAD_GROUP_STRUCTURE', `${b.left} bytes after the tokens`);
    for (const k of tree) {
      if (k >= 0xfffffff0 && k < IN_LEAF) fail('BAD_GROUP_STRUCTURE', `reserved token ${k}`);
      if (k < 0xfffffff0 && k >= m) fail('BAD_GROUP_STRUCTURE', `split on ${k}, ${m} references`);
    }
  } else {
    const t = b.varint();
    if (t > b.left) fail('BAD_GROUP_STRUCTURE', `${t} tokens in ${b.left} bytes`);
    const raw = [];
    for (let i = 0; i < t; i++) raw.push(b.varint());
    if (b.left > 0) fail('BAD_GROUP_STRUCTURE', `${b.left} bytes after the tokens`);
    for (const k of raw) {
      if (k > m + 1) fail('BAD_GROUP_STRUCTURE', `token ${k}, ${m} references`);
      tree.push(k === 0 ? IN_LEAF : k === 1 ? OUT_LEAF : k - 2);
    }
  }
  let slots = 1;
  for (let i = 0; i < tree.length; i++) {
    if (slots <= 0) fail('BAD_GROUP_STRUCTURE', 'tokens after a complete tree');
    slots += tree[i] >= IN_LEAF ? -1 : 1;
  }
  if (tree.length === 0 || slots !== 0) fail('BAD_GROUP_STRUCTURE', 'not one complete tree');
  return { tree };
}
