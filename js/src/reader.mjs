/** The container reader: every chunk (and in version 6 every record of every body segment) in file order, with the checks of spec §12.1 in their order. */
import { fail, PlnError } from './errors.mjs';
import { checkSignature, readChunk } from './chunks.mjs';
import { parseHeader } from './header.mjs';
import { PlaneTable, readPlanes, readPlanesRecord } from './planes.mjs';
import { readObject } from './objects.mjs';
import { readGroup, readGroupRecord, NEWEST_MINOR } from './groups.mjs';
import { readColours, checkIndex, checkIndex6, readMetadata } from './ancillary.mjs';
import { segmentBytes, forEachRecord, RECORDS } from './segments.mjs';
import { DEFAULT_LIMITS } from './compression.mjs';
import { Budget } from './budget.mjs';

const KNOWN = new Set(['PHDR', 'OBJT', 'PLNS', 'GRUP', 'cOLR', 'iNDX', 'mETA', 'PEND']);
/** Version 6's critical chunks: the others' payloads are records of body segments. */
const KNOWN6 = new Set(['PHDR', 'BODY', 'PEND']);
/** The chunk types of versions 1 to 5 that version 6 makes records. */
const RECORD_CHUNKS = new Set(['OBJT', 'PLNS', 'GRUP', 'cOLR', 'mETA']);

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
 * @property {{type: string, records: number, bytes: number}[]} records version 6: per record type ('OBJT', 'PLNS',
 *   'GRUP', 'cOLR', 'mETA', or 'tag N' for an ancillary one), in the order first met, its records and their raw
 *   bytes (tag and length included) in all; empty before version 6
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
  /** @type {import('./compression.mjs').Codecs} */
  const codecs = { inflate: options.inflate ?? null, brotli: options.brotli ?? null };
  checkSignature(bytes);
  /** @type {Contents | null} */
  let contents = null;
  /** @type {Container['chunks']} */
  const chunks = [];
  let indexOffset = -1;
  let pos = 8;
  for (;;) {
    let chunk;
    try {
      // PHDR's length is a u32 in every version; from version 5 on, later chunks have varint32 lengths (§4.1)
      chunk = readChunk(bytes, pos, limits.chunkLength, contents !== null && contents.header.version[0] >= 5);
    } catch (err) {
      if (err instanceof PlnError) err.offset = pos;
      throw err;
    }
    const { type, offset, payload } = chunk;
    try {
      if (!contents && type !== 'PHDR') fail('MISSING_HEADER', `first chunk ${type}`);
      if (indexOffset >= 0 && type !== 'PEND') fail('CHUNK_ORDER', `${type} after iNDX`);
      if (contents && type === 'PHDR') fail('DUPLICATE_HEADER', 'a second PHDR');
      const v6 = contents !== null && contents.header.version[0] >= 6;
      // version 6: objects, planes, groups, colours and metadata are records of body segments
      if (v6 && RECORD_CHUNKS.has(type)) fail('CHUNK_ORDER', `${type}: a record of a body segment in version 6`);
      const critical = (chunk.type.charCodeAt(0) & 0x20) === 0;
      if (critical && !(v6 ? KNOWN6 : KNOWN).has(type)) fail('UNKNOWN_CRITICAL_CHUNK', type);
      const size = chunk.head + chunk.length + 4;
      chunks.push({ type, offset, length: chunk.length, size });
      pos = offset + size;
      if (type === 'PHDR') {
        const { header, segment } = parseHeader(payload);
        contents = new Contents(header, limits, codecs);
        const [major, minor] = header.version;
        if (minor > NEWEST_MINOR[/** @type {1|2|3|4|5|6} */ (major)]) contents.findings.add('NEWER_MINOR_VERSION');
        if (segment.length > 0) contents.segment(segment, offset);
        continue;
      }
      const c = /** @type {Contents} */ (contents);
      if (type === 'BODY') c.segment(payload, offset);
      else if (type === 'iNDX') {
        if (v6) checkIndex6(payload, offset, c.listed);
        else checkIndex(payload, offset, chunks[1].offset, c.listed);
        indexOffset = offset;
      } else if (type === 'PEND') {
        checkEnd(payload, c.header, indexOffset, { planes: c.table.count, objects: c.objects.length, groups: c.groups.length });
        if (pos !== bytes.length) fail('TRAILING_DATA', `${bytes.length - pos} bytes after PEND`);
        break;
      } else if (RECORD_CHUNKS.has(type)) c.record(type, payload, { offset, raw: 0 });
      else c.findings.add('UNKNOWN_ANCILLARY_CHUNK');
    } catch (err) {
      if (err instanceof PlnError && err.offset === null) {
        err.chunk = type;
        err.offset = offset;
      }
      throw err;
    }
  }
  const c = /** @type {Contents} */ (contents);
  return {
    header: c.header, chunks, planes: c.table.view(), objects: c.objects, groups: c.groups, colours: c.colours,
    metadata: c.metadata, findings: c.findings, budget: c.budget, records: c.records,
  };
}

/** What a file holds as read so far: the payloads of OBJT, PLNS, GRUP, cOLR and mETA, as chunks or records. */
class Contents {
  /**
   * @param {import('./header.mjs').Header} header
   * @param {import('./compression.mjs').Limits} limits
   * @param {import('./compression.mjs').Codecs} codecs
   */
  constructor(header, limits, codecs) {
    this.header = header;
    this.limits = limits;
    this.codecs = codecs;
    this.budget = new Budget(limits);
    this.table = new PlaneTable();
    /** @type {import('./objects.mjs').PlnObject[]} */
    this.objects = [];
    /** @type {import('./groups.mjs').Group[]} */
    this.groups = [];
    /** @type {Container['colours']} */
    this.colours = [];
    /** where each group's colours are in `colours` @type {Map<number, number>} */
    this.colourAt = new Map();
    /** @type {Record<string, string>} */
    this.metadata = Object.create(null);
    /** @type {Set<string>} */
    this.findings = new Set();
    /** the OBJT, PLNS and GRUP chunks or records read, for the index: raw is a record's offset in its segment
     * @type {{offset: number, raw: number, type: string, ordinal: number}[]} */
    this.listed = [];
    /** @type {Container['records']} */
    this.records = [];
    /** where each record type is in `records` @type {Map<string, number>} */
    this.recordAt = new Map();
  }

  /**
   * A version 6 body segment: decompressed, its records read, and let go.
   * @param {Uint8Array} stored @param {number} offset the chunk's (PHDR or BODY)
   */
  segment(stored, offset) {
    forEachRecord(segmentBytes(stored, this.limits, this.codecs), (tag, payload, raw, size) => {
      const type = RECORDS[tag];
      this.count(type ?? `tag ${tag}`, size);
      if (type) this.record(type, payload, { offset, raw });
      else if (tag >= 128) this.findings.add('UNKNOWN_ANCILLARY_CHUNK');
      else fail('UNKNOWN_CRITICAL_CHUNK', `record tag ${tag}`);
    });
  }

  /** @param {string} type @param {number} size a record's raw bytes */
  count(type, size) {
    const at = this.recordAt.get(type);
    if (at === undefined) {
      this.recordAt.set(type, this.records.length);
      this.records.push({ type, records: 1, bytes: size });
    } else {
      this.records[at].records += 1;
      this.records[at].bytes += size;
    }
  }

  /**
   * One OBJT, PLNS, GRUP, cOLR or mETA payload: a chunk's (versions 1 to 5) or a record's (6).
   * @param {string} type @param {Uint8Array} payload @param {{offset: number, raw: number}} at where it is, for the index
   */
  record(type, payload, at) {
    const h = this.header;
    const major = h.version[0];
    if (type === 'PLNS') {
      this.listed.push({ ...at, type, ordinal: this.table.count });
      if (major >= 6) readPlanesRecord(payload, h, this.table, this.limits);
      else readPlanes(payload, h, this.table, this.limits, this.codecs);
    } else if (type === 'OBJT') {
      this.listed.push({ ...at, type, ordinal: this.objects.length });
      this.objects.push(readObject(payload, major, this.objects.length, this.limits));
    } else if (type === 'GRUP') {
      this.listed.push({ ...at, type, ordinal: this.groups.length });
      const ctx = {
        version: h.version, groups: this.groups.length, earlier: this.groups, objects: this.objects.length,
        planes: this.table.count, limits: this.limits, codecs: this.codecs, budget: this.budget,
      };
      const g = major >= 6 ? readGroupRecord(payload, ctx) : readGroup(payload, ctx);
      if (g.skipped) this.findings.add('SKIPPED_GROUP_KIND');
      this.groups.push(g);
      this.objects[g.object].groups.push(g);
    } else if (type === 'cOLR') {
      // replaced, not kept beside: every cOLR of one group expanded and listed would let a few
      // 12-byte chunks of a large group cost memory without bound (fuzz/hostile.py x_colour_expansion)
      const read = readColours(payload, this.groups, major);
      const at = this.colourAt.get(read.group);
      if (at === undefined) {
        this.colourAt.set(read.group, this.colours.length);
        this.colours.push(read);
      } else this.colours[at] = read;
    } else {
      if (this.listed.length > 0) fail('BAD_METADATA', 'mETA after an OBJT, PLNS or GRUP');
      readMetadata(payload, this.metadata, major);
    }
  }
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
