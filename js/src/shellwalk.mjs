/**
 * Shell walks (kind 9, spec §9.13, version 4.1), shell walks with multi-parallelograms (kind 10,
 * §9.14, version 4.2), shell walks with reflections (kind 12, §9.16, version 5.1) and shell walks
 * stepping from the later gate corner (kind 13, §9.17, version 5.2): the same data, kinds 10, 12 and
 * 13 another prediction of explicit corners (in shelltree.mjs), read into the Shell structure of
 * shells.mjs.
 *
 * A walk is a shell tree (§9.11) whose tree is a depth-first walk (a stack of slots, one symbol per
 * triangle naming the edges that have children) and whose third corners are mostly "left" or
 * "right": the far end of the newest open edge at one of the triangle's first two corners. What
 * follows the corner codes (faces, named corners, picks, explicit corners) is §9.11's, read by
 * shelltree.mjs's shellTreeRest with the links and corners the walk gives.
 *
 * The open edges (§9.13) are kept as the spec suggests, so that each triangle takes constant time
 * whatever the file holds: a map from each directed edge to the stack of its entries, and per corner
 * two doubly linked lists of the entries starting and ending there, newest first. All of it lives in
 * typed arrays; the map is an open-addressing hash table of undirected edges, each slot with the newest
 * entry of both directions (linear probing, a hash keyed per walk) rather than a JavaScript Map, whose keys would have to pack two corner numbers into
 * one exact number (a·V + b passes 2^53 for V above 9.5e7) and which V8 caps at 2^24 entries, fewer
 * than the open edges a valid file of disjoint triangles can hold.
 */
import { fail } from './errors.mjs';
import { NO_CHARGE } from './budget.mjs';
import { readBits } from './varint.mjs';
import { readVarints } from './shells.mjs';
import { shellTreeRest } from './shelltree.mjs';

/** The ordered lists of children of a root (free edges 0, 1, 2), by symbol (§9.13). */
const ROOT_CHILDREN = [
  [], [0], [1], [2], [0, 1], [0, 2], [1, 0], [1, 2], [2, 0], [2, 1],
  [0, 1, 2], [0, 2, 1], [1, 0, 2], [1, 2, 0], [2, 0, 1], [2, 1, 0],
];

/** The same for an attached triangle (free edges 1, 2), by ⌊symbol / 4⌋. */
const ATTACHED_CHILDREN = [[], [1], [2], [1, 2], [2, 1]];

/**
 * The open edges of §9.13: directed edges (a, b), each entry numbered in order of entry (newest the
 * highest), with the newest entry of an edge found by the edge and the newest entries starting or
 * ending at a corner found by the corner.
 */
export class OpenEdges {
  /**
   * @param {number} corners corner numbers are below this
   * @param {number} capacity entries ever made (three per triangle at most)
   */
  constructor(corners, capacity) {
    this.start = new Int32Array(capacity);
    this.end = new Int32Array(capacity);
    /** the entry of the same edge below this one on its stack, -1 for none */
    this.below = new Int32Array(capacity);
    this.outNext = new Int32Array(capacity);
    this.outPrev = new Int32Array(capacity);
    this.inNext = new Int32Array(capacity);
    this.inPrev = new Int32Array(capacity);
    /** per corner the newest entry starting (out) or ending (in) there, -1 for none */
    this.outHead = new Int32Array(corners).fill(-1);
    this.inHead = new Int32Array(corners).fill(-1);
    this.entries = 0;
    // The hash table: one slot per undirected edge {lo, hi} (lo -1: empty), holding the newest entry
    // of (lo, hi) at 2i and of (hi, lo) at 2i + 1, -1 for none: entering (a, b) closes an entry of
    // (b, a) or stacks one on (a, b), both found by one probe. Slots stay once made.
    // Sized for a closed surface's edges (half the entries) at half load: growing by doubling from a
    // small table rehashed it a dozen times, a seventh of a walk's decode (CAD/box.STL).
    let size = 64;
    while (size < capacity && size < 0x40000000) size *= 2;
    this.lo = new Int32Array(size).fill(-1);
    this.hi = new Int32Array(size);
    this.top = new Int32Array(2 * size).fill(-1);
    this.mask = size - 1;
    this.keys = 0;
    // the bytes a corner below `corners` can have: the others are zero in every key, and their tables
    // would only xor a constant into every hash
    this.bytes = corners > 0x1000000 ? 4 : corners > 0x10000 ? 3 : corners > 0x100 ? 2 : 1;
    this.tables = globalThis.crypto.getRandomValues(new Int32Array(512 * this.bytes));
  }

  /**
   * Simple tabulation hashing with tables drawn per walk (§9.13): a fixed hash lets a file put every
   * edge into a few slots, each probe then passing every edge already there (a kind 9 walk of
   * 100,000 such edges took 53 s); with random tables linear probing takes expected constant time.
   * @param {number} a @param {number} b
   */
  hash(a, b) {
    const t = this.tables;
    let h = t[a & 255] ^ t[256 + (b & 255)];
    for (let k = 1; k < this.bytes; k++) h ^= t[512 * k + ((a >>> (8 * k)) & 255)] ^ t[512 * k + 256 + ((b >>> (8 * k)) & 255)];
    return h & this.mask;
  }

  /**
   * Edge (a, b) of a triangle: closes the newest entry (b, a) where there is one, else enters (a, b)
   * as the newest entry.
   * @param {number} a @param {number} b
   */
  edge(a, b) {
    const lo = a < b ? a : b;
    const hi = a < b ? b : a;
    const d = a < b ? 0 : 1; // the direction of (a, b) in its slot, 1 - d that of (b, a)
    let i = this.slot(lo, hi);
    if (this.lo[i] >= 0) {
      const e = this.top[2 * i + 1 - d];
      if (e >= 0) {
        this.top[2 * i + 1 - d] = this.below[e];
        this.unlink(e);
        return;
      }
    } else {
      if (2 * (this.keys + 1) > this.lo.length) {
        this.grow();
        i = this.slot(lo, hi);
      }
      this.lo[i] = lo;
      this.hi[i] = hi;
      this.top[2 * i] = this.top[2 * i + 1] = -1;
      this.keys++;
    }
    const e = this.entries++;
    this.start[e] = a;
    this.end[e] = b;
    this.below[e] = this.top[2 * i + d];
    this.top[2 * i + d] = e;
    const { outHead, inHead } = this;
    this.outPrev[e] = -1;
    this.outNext[e] = outHead[a];
    if (outHead[a] >= 0) this.outPrev[outHead[a]] = e;
    outHead[a] = e;
    this.inPrev[e] = -1;
    this.inNext[e] = inHead[b];
    if (inHead[b] >= 0) this.inPrev[inHead[b]] = e;
    inHead[b] = e;
  }

  /** The slot of {lo, hi}: its own, or the empty one where it would go. @param {number} lo @param {number} hi */
  slot(lo, hi) {
    const { mask } = this;
    let i = this.hash(lo, hi);
    while (this.lo[i] >= 0 && (this.lo[i] !== lo || this.hi[i] !== hi)) i = (i + 1) & mask;
    return i;
  }

  /** Takes entry e out of its corners' lists. @param {number} e */
  unlink(e) {
    const { outNext, outPrev, inNext, inPrev } = this;
    let p = outPrev[e];
    let q = outNext[e];
    if (p >= 0) outNext[p] = q;
    else this.outHead[this.start[e]] = q;
    if (q >= 0) outPrev[q] = p;
    p = inPrev[e];
    q = inNext[e];
    if (p >= 0) inNext[p] = q;
    else this.inHead[this.end[e]] = q;
    if (q >= 0) inPrev[q] = p;
  }

  grow() {
    const { lo, hi, top } = this;
    this.lo = new Int32Array(2 * lo.length).fill(-1);
    this.hi = new Int32Array(2 * lo.length);
    this.top = new Int32Array(4 * lo.length).fill(-1);
    this.mask = this.lo.length - 1;
    for (let i = 0; i < lo.length; i++) {
      if (lo[i] < 0) continue;
      const s = this.slot(lo[i], hi[i]);
      this.lo[s] = lo[i];
      this.hi[s] = hi[i];
      this.top[2 * s] = top[2 * i];
      this.top[2 * s + 1] = top[2 * i + 1];
    }
  }

  /**
   * Left (§9.13): the start of the newest open edge ending at `corner`, or, where that is `not`,
   * of the second newest; -1 where there is none.
   * @param {number} corner @param {number} not
   */
  left(corner, not) {
    let e = this.inHead[corner];
    if (e < 0) return -1;
    if (this.start[e] !== not) return this.start[e];
    e = this.inNext[e];
    return e < 0 ? -1 : this.start[e];
  }

  /**
   * Right (§9.13): the end of the newest open edge starting at `corner`, or, where that is `not`,
   * of the second newest; -1 where there is none.
   * @param {number} corner @param {number} not
   */
  right(corner, not) {
    let e = this.outHead[corner];
    if (e < 0) return -1;
    if (this.end[e] !== not) return this.end[e];
    e = this.outNext[e];
    return e < 0 ? -1 : this.end[e];
  }
}

/**
 * Kind 9 data, read and checked in §9.13's order; kind 10 (§9.14) is the same data with its explicit
 * corners predicted by averaged parallelograms where they have any, kind 12 (§9.16) by the turn of
 * the two steps before them where those turn, kind 13 (§9.17) stepping from the later-named corner
 * of their gate (max(i0, i1)) rather than from i0.
 * @param {import('./varint.mjs').Cursor} b
 * @param {Uint8Array} roles
 * @param {9 | 10 | 12 | 13} [kind]
 * @param {boolean} [f32Grid] version 5: the grid in f32 (§9.10)
 * @returns {import('./shells.mjs').Shell}
 * @param {import('./budget.mjs').Charge} [charge] takes the declared counts once checked, before
 *   anything of their size is allocated (§12.4)
 */
export function readShellWalk(b, roles, kind = 9, f32Grid = false, charge = NO_CHARGE) {
  const V = b.varint();
  const T = b.varint();
  const X = b.varint();
  const left = b.left;
  if (V < 3 || V > 8 * left || T < 1 || 2 * T > left || X > left) {
    fail('BAD_GROUP_STRUCTURE', `counts V=${V} T=${T} X=${X} for ${left} bytes`);
  }
  charge(V, T);
  const symbols = readVarints(b, T);
  const escapes = readVarints(b, X);
  const faceCodes = readVarints(b, T);
  const explicit = readBits(b, V);

  // T triangles name at most 3T corners, so a larger V fails below (n ≠ V) whatever the walk
  // holds: refused here, before anything of V's size is allocated beyond the flags
  if (V > 3 * T) fail('BAD_GROUP_STRUCTURE', `${V} corners, at most ${3 * T} named`);
  // entries are numbered in 32-bit integers: 3T of them (a body of 1.4 GB and more) is this
  // reader's limit (§12.4), far above the default raw size limit
  if (3 * T > 0x7fffffff) fail('LIMIT_EXCEEDED', `${T} triangles in a walk`);
  const tri = new Uint32Array(3 * T);
  const namer = new Int32Array(V); // the attached triangle whose code names each corner anew, -1 for a root's
  const parent = new Int32Array(T);
  const opposite = new Int32Array(T);
  // the slots (triangle, edge) as 3 × triangle + edge; a root finds the stack empty and leaves 3
  // slots, an attached triangle takes one and leaves at most 2: at most T + 2 at a time
  const stack = new Float64Array(T + 2);
  let top = 0;
  const open = new OpenEdges(V, 3 * T);
  let n = 0;
  let x = 0; // escapes used
  for (let j = 0; j < T; j++) {
    const s = symbols[j];
    let i0;
    let i1;
    let i2;
    let children;
    if (top === 0) {
      if (s >= 16) fail('BAD_GROUP_STRUCTURE', `root ${j}: symbol ${s}`);
      children = ROOT_CHILDREN[s];
      if (x + 3 > X) fail('BAD_GROUP_STRUCTURE', `root ${j}: fewer escapes than the walk uses`);
      parent[j] = -1;
      opposite[j] = -1;
      const c0 = escapes[x];
      const c1 = escapes[x + 1];
      const c2 = escapes[x + 2];
      x += 3;
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
      if (s >= 20) fail('BAD_GROUP_STRUCTURE', `triangle ${j}: symbol ${s}`);
      children = ATTACHED_CHILDREN[s >>> 2];
      const slot = stack[--top];
      const p = Math.floor(slot / 3);
      const e = slot - 3 * p;
      parent[j] = p;
      i0 = tri[3 * p + (e === 2 ? 0 : e + 1)];
      i1 = tri[3 * p + e];
      const o = tri[3 * p + (e === 0 ? 2 : e - 1)];
      opposite[j] = o;
      const k = s & 3;
      if (k === 0) {
        if (n >= V) fail('BAD_GROUP_STRUCTURE', `more than ${V} corners named`);
        namer[(i2 = n++)] = j;
      } else if (k === 1) {
        i2 = open.left(i1, o);
        if (i2 < 0) fail('BAD_GROUP_STRUCTURE', `triangle ${j}: left with no open edge to name`);
      } else if (k === 2) {
        i2 = open.right(i0, o);
        if (i2 < 0) fail('BAD_GROUP_STRUCTURE', `triangle ${j}: right with no open edge to name`);
      } else {
        if (x >= X) fail('BAD_GROUP_STRUCTURE', `triangle ${j}: fewer escapes than the walk uses`);
        const z = escapes[x++];
        // |z(k - 3)| < n for any corner named before, so z < 2n keeps to small integers
        if (z >= 2 * n) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names a corner not named before`);
        i2 = i1 + (z % 2 === 1 ? -(z + 1) / 2 : z / 2);
        if (i2 < 0 || i2 >= n) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names a corner not named before`);
      }
    }
    if (i0 === i1 || i1 === i2 || i0 === i2) fail('BAD_GROUP_STRUCTURE', `triangle ${j} names one corner twice`);
    tri[3 * j] = i0;
    tri[3 * j + 1] = i1;
    tri[3 * j + 2] = i2;
    open.edge(i0, i1);
    open.edge(i1, i2);
    open.edge(i2, i0);
    for (let q = children.length - 1; q >= 0; q--) stack[top++] = 3 * j + children[q];
  }
  if (top !== 0) fail('BAD_GROUP_STRUCTURE', `${top} slots left on the stack after the last triangle`);
  if (x !== X) fail('BAD_GROUP_STRUCTURE', `${X - x} escapes left over`);
  if (n !== V) fail('BAD_GROUP_STRUCTURE', `${n} corners named, ${V} declared`);
  return shellTreeRest(b, roles, { V, T, explicit, tri, namer, parent, opposite, faceCodes }, { parallelogram: false, walk: true, multi: kind === 10, reflect: kind === 12, later: kind === 13, f32Grid });
}
