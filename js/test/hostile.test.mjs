// Damaged copies of every valid golden file, their CRCs recomputed so that the damage reaches the
// payload parsers and decoders: each must be read or refused with a PlnError, never crash.
import { test } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { readPln, PlnError } from '../src/node.mjs';
import { crc32 } from '../src/crc32.mjs';
import { VALID, golden } from './files.mjs';

const COPIES = 150;

/** A small deterministic generator (mulberry32), so that a failure repeats. @param {number} seed */
function random(seed) {
  let a = seed;
  return () => {
    a = (a + 0x6d2b79f5) | 0;
    let t = Math.imul(a ^ (a >>> 15), 1 | a);
    t = (t + Math.imul(t ^ (t >>> 7), 61 | t)) ^ t;
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

/**
 * Where the payloads of an intact file's chunks are: its chunk list as readPln reads it (a chunk
 * head is 8 bytes, or in version 5 after PHDR 5 to 9, its length a varint, §4.1).
 * @param {Uint8Array} b
 */
function chunksOf(b) {
  return readPln(b, { decode: false }).chunks.map((c) => ({ pos: c.offset, start: c.offset + c.size - 4 - c.length, length: c.length }));
}

/** Damage one chunk's payload (a byte set, a bit flipped, a run zeroed) and fix its CRC. */
function damage(/** @type {Uint8Array} */ bytes, /** @type {() => number} */ rnd) {
  const b = bytes.slice();
  const chunks = chunksOf(b).filter((c) => c.length > 0);
  const c = chunks[Math.floor(rnd() * chunks.length)];
  const at = c.start + Math.floor(rnd() * c.length);
  const how = rnd();
  if (how < 0.4) b[at] = Math.floor(rnd() * 256);
  else if (how < 0.8) b[at] ^= 1 << Math.floor(rnd() * 8);
  else b.fill(how < 0.9 ? 0 : 0xff, at, Math.min(at + 1 + Math.floor(rnd() * 8), c.start + c.length));
  const end = c.start + c.length;
  const crc = crc32(b, c.start, end, crc32(b, c.pos, c.pos + 4));
  new DataView(b.buffer).setUint32(end, crc, true);
  return b;
}

for (const name of fs.readdirSync(VALID).filter((f) => f.endsWith('.pln'))) {
  test(`${COPIES} damaged copies of ${name}`, () => {
    const bytes = golden(name);
    const rnd = random(name.length * 7919 + bytes.length);
    for (let i = 0; i < COPIES; i++) {
      const b = i % 10 === 9 ? bytes.subarray(0, Math.floor(rnd() * bytes.length)) : damage(bytes, rnd);
      try {
        readPln(b, { decode: true });
      } catch (err) {
        assert.ok(err instanceof PlnError, `copy ${i}: ${/** @type {Error} */ (err).stack}`);
      }
    }
  });
}
