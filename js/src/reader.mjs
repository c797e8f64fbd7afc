/** The container reader: every chunk in file order, with the checks of spec §12.1 in their order. */
import { fail, PlnError } from './errors.mjs';
import { checkSignature, readChunk } from './chunks.mjs';
import { parseHeader } from './header.mjs';
import { PlaneTable, readPlanes } from './planes.mjs';
import { readObject } from './objects.mjs';
import { readGroup, NEWEST_MINOR } from './groups.mjs';
import { readColours, checkIndex, readMetadata } from './ancillary.mjs';
import { DEFAULT_LIMITS } from './compression.mjs';
import { Budget } from './budget.mjs';

const KNOWN = new Set(['PHDR', 'OBJT', 'PLNS', 'GRUP', 'cOLR', 'iNDX', 'mETA', 'PEND']);

/**
 * @typedef {object} Container
 * @property {import('./header.mjs').Header} header
 * @property {{type: string, offset: number, length: number, size: number}[]} chunks size: the whole chunk's bytes (head, payload, CRC)
 * @property {Float64Array} planes (ν, φ, h) triplets
 * @property {import('./objects.mjs').PlnObject[]} objects
 * @property {import('./groups.mjs').Group[]} groups in file order
 * @property {{group: number, rgba: Uint8Array}[]} colours the colours of each coloured group, in the order of its
 *   first cOLR; a later cOLR of the same group replaces the earlier one (§10.1: the last applies)
 * @property {Record<string, string>} metadata every mETA chunk (a version 5 header's up axis is in header.up_axis)
 * @property {Set<string>} findings §12.3 codes
 * @property {Budget} budget the output charged so far (§12.4): the declared counts; a decoder adds the rest
 */

/**
 * @param {Uint8Array} bytes a whole file
 * @param {{limits?: Partial<import('./compression.mjs').Limits>, inflate?: import('./compression.mjs').InflateFn | null,
 *   brotli?: import('./compression.mjs').BrotliFn | null}} [options]
 * @returns {Container}
 */
export function readContainer(bytes, options = {}) {
  const limits = { ...DEFAULT_LIMITS, ...options.limits };
  const budget = new Budget(limits);
  /** @type {import('./compression.mjs').Codecs} */
  const codecs = { inflate: options.inflate ?? null, brotli: options.brotli ?? null };
  checkSignature(bytes);
  /** @type {import('./header.mjs').Header | null} */
  let header = null;
  const table = new PlaneTable();
  /** @type {Container['chunks']} */
  const chunks = [];
  /** @type {import('./objects.mjs').PlnObject[]} */
  const objects = [];
  /** @type {import('./groups.mjs').Group[]} */
  const groups = [];
  /** @type {Container['colours']} */
  const colours = [];
  /** where each group's colours are in `colours` @type {Map<number, number>} */
  const colourAt = new Map();
  /** @type {Record<string, string>} */
  const metadata = Object.create(null);
  const findings = new Set();
  /** @type {{offset: number, type: string, ordinal: number}[]} */
  const listed = [];
  let indexOffset = -1;
  let pos = 8;
  for (;;) {
    let chunk;
    try {
      // PHDR's length is a u32 in every version; a version 5 file's later chunks have varint32 lengths (§4.1)
      chunk = readChunk(bytes, pos, limits.chunkLength, header !== null && header.version[0] >= 5);
    } catch (err) {
      if (err instanceof PlnError) err.offset = pos;
      throw err;
    }
    const { type, offset, payload } = chunk;
    try {
      if (!header && type !== 'PHDR') fail('MISSING_HEADER', `first chunk ${type}`);
      if (indexOffset >= 0 && type !== 'PEND') fail('CHUNK_ORDER', `${type} after iNDX`);
      if (header && type === 'PHDR') fail('DUPLICATE_HEADER', 'a second PHDR');
      const critical = (chunk.type.charCodeAt(0) & 0x20) === 0;
      if (critical && !KNOWN.has(type)) fail('UNKNOWN_CRITICAL_CHUNK', type);
      const size = chunk.head + chunk.length + 4;
      chunks.push({ type, offset, length: chunk.length, size });
      pos = offset + size;
      if (type === 'PHDR') {
        header = parseHeader(payload);
        const [major, minor] = header.version;
        if (minor > NEWEST_MINOR[/** @type {1|2|3|4|5} */ (major)]) findings.add('NEWER_MINOR_VERSION');
        continue;
      }
      const h = /** @type {import('./header.mjs').Header} */ (header);
      if (type === 'PLNS') {
        listed.push({ offset, type, ordinal: table.count });
        readPlanes(payload, h, table, limits, codecs);
      } else if (type === 'OBJT') {
        listed.push({ offset, type, ordinal: objects.length });
        objects.push(readObject(payload, h.version[0], objects.length, limits));
      } else if (type === 'GRUP') {
        listed.push({ offset, type, ordinal: groups.length });
        const g = readGroup(payload, {
          version: h.version, groups: groups.length, earlier: groups, objects: objects.length, planes: table.count, limits, codecs, budget,
        });
        if (g.skipped) findings.add('SKIPPED_GROUP_KIND');
        groups.push(g);
        objects[g.object].groups.push(g);
      } else if (type === 'cOLR') {
        // replaced, not kept beside: every cOLR of one group expanded and listed would let a few
        // 12-byte chunks of a large group cost memory without bound (fuzz/hostile.py x_colour_expansion)
        const read = readColours(payload, groups, h.version[0]);
        const at = colourAt.get(read.group);
        if (at === undefined) { colourAt.set(read.group, colours.length); colours.push(read); } else colours[at] = read;
      } else if (type === 'mETA') {
        if (listed.length > 0) fail('BAD_METADATA', 'mETA after an OBJT, PLNS or GRUP');
        readMetadata(payload, metadata, h.version[0]);
      } else if (type === 'iNDX') {
        checkIndex(payload, offset, chunks[1].offset, listed);
        indexOffset = offset;
      } else if (type === 'PEND') {
        checkEnd(payload, h, indexOffset, { planes: table.count, objects: objects.length, groups: groups.length });
        if (pos !== bytes.length) fail('TRAILING_DATA', `${bytes.length - pos} bytes after PEND`);
        break;
      } else {
        findings.add('UNKNOWN_ANCILLARY_CHUNK');
      }
    } catch (err) {
      if (err instanceof PlnError && err.offset === null) {
        err.chunk = type;
        err.offset = offset;
      }
      throw err;
    }
  }
  return {
    header: /** @type {import('./header.mjs').Header} */ (header),
    chunks, planes: table.view(), objects, groups, colours, metadata, findings, budget,
  };
}

/**
 * PEND (§4.4, A.1): payload length, index offset, counts; trailing bytes are the caller's.
 * @param {Uint8Array} payload
 * @param {import('./header.mjs').Header} header
 * @param {number} indexOffset -1 without an iNDX
 * @param {{planes: number, objects: number, groups: number}} read
 */
function checkEnd(payload, header, indexOffset, read) {
  const old = header.version[0] < 3;
  if (old ? payload.length !== 8 : payload.length !== 0 && payload.length !== 8) {
    fail('BAD_PAYLOAD', `PEND of ${payload.length} bytes`);
  }
  if (payload.length === 8) {
    const view = new DataView(payload.buffer, payload.byteOffset, 8);
    const at = view.getUint32(4, true) * 4294967296 + view.getUint32(0, true);
    // versions 1 and 2 write 0 for "no index"; versions 3 to 5 write an empty PEND instead
    if (!(old && at === 0) && (at === 0 || at !== indexOffset)) fail('BAD_INDEX', `PEND index offset ${at}`);
  }
  const counts = header.counts;
  if (counts && (counts.planes !== read.planes || counts.objects !== read.objects || counts.groups !== read.groups)) {
    fail('COUNT_MISMATCH', `header counts ${JSON.stringify(counts)}, read ${JSON.stringify(read)}`);
  }
}
