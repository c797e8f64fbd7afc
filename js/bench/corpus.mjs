/** The real corpus as .pln files made by planefmt's default encoder, for the tests and benchmarks. */
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import crypto from 'node:crypto';
import { execFileSync } from 'node:child_process';
import { fileURLToPath } from 'node:url';

/** The planefmt checkout whose .venv encodes and decodes: this repository, or PLANEFMT_ROOT (another
 * worktree, e.g. one whose writer is newer than this one's). */
export const ROOT = process.env.PLANEFMT_ROOT ?? path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
export const PYTHON = path.join(ROOT, '.venv/bin/python');
const PLN = path.join(ROOT, '.venv/bin/pln');
// as tests/corpus.py: PLN_CORPUS, or the repository's tests/corpus
export const CORPUS = process.env.PLN_CORPUS ?? path.join(ROOT, 'tests', 'corpus');

/** Whether planefmt (the repository's .venv) and the corpus are here. */
export const available = fs.existsSync(PLN) && fs.existsSync(CORPUS);

/** Every mesh file of the corpus, relative to it (a glTF's .bin goes with its .gltf). */
export function allFiles() {
  return fs.readdirSync(CORPUS, { withFileTypes: true }).filter((d) => d.isDirectory())
    .flatMap((d) => fs.readdirSync(path.join(CORPUS, d.name)).map((f) => `${d.name}/${f}`))
    .filter((f) => !f.endsWith('.bin') && !f.endsWith('.md')).sort();
}

let version = '';

/** @type {number[] | null} */
let majors = null;

/**
 * The major versions `pln convert --major` writes (its help's choices), e.g. [3, 4, 5, 6]; empty
 * without planefmt.
 */
export function encoderMajors() {
  if (majors) return majors;
  if (!available) return (majors = []);
  const help = execFileSync(PLN, ['convert', '--help'], { encoding: 'utf8' });
  const choices = /--major \{([\d,]+)\}/.exec(help);
  majors = choices ? choices[1].split(',').map(Number) : [];
  return majors;
}

/**
 * What the encoder is: a digest of planefmt's and the converters' sources, whose package version does
 * not change with every encoder change (a cache keyed on `pln --version` alone kept files of an older
 * encoder, without the kind 8 groups of version 3.4).
 */
function encoderVersion() {
  const hash = crypto.createHash('sha1');
  const walk = (dir) => {
    for (const entry of fs.readdirSync(dir, { withFileTypes: true }).sort((a, b) => (a.name < b.name ? -1 : 1))) {
      const full = path.join(dir, entry.name);
      if (entry.isDirectory()) walk(full);
      else if (/\.(py|c)$/.test(entry.name)) hash.update(entry.name).update(fs.readFileSync(full));
    }
  };
  walk(path.join(ROOT, 'planefmt'));
  walk(path.join(ROOT, 'converters'));
  return hash.digest('hex');
}

/**
 * The .pln of a corpus file, encoded by `pln convert` once per source, options and encoder
 * version and kept in the temporary directory.
 * @param {string} rel a path relative to the corpus
 * @param {string[]} [options] of `pln convert`, e.g. ['--scheme', 'paper']
 */
export function encoded(rel, options = []) {
  version ||= encoderVersion();
  const src = path.join(CORPUS, rel);
  const stat = fs.statSync(src);
  const key = crypto.createHash('sha1').update(`${rel}\0${stat.size}\0${stat.mtimeMs}\0${version}\0${options.join(' ')}`)
    .digest('hex').slice(0, 16);
  const dir = path.join(os.tmpdir(), 'planefmt-js-corpus');
  fs.mkdirSync(dir, { recursive: true });
  const out = path.join(dir, `${path.basename(rel).replace(/\W/g, '_')}-${key}.pln`);
  if (!fs.existsSync(out)) execFileSync(PLN, ['convert', ...options, src, out], { stdio: ['ignore', 'ignore', 'pipe'] });
  return out;
}
