/**
 * A screenshot of the viewer (docs/viewer.png) in headless Chromium, as the viewer's test runs it.
 *
 *   node js/viewer/screenshot.mjs [SOURCE] [OUT.png] [--up Y|Z] [--size WxH]
 *
 * SOURCE: a .pln, or any mesh `pln convert` reads (encoded with its defaults into a temporary
 * .pln); default the corpus's cad/featuretype.STL, shown +z up. OUT: default docs/viewer.png.
 */
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { serve, JS_ROOT } from './serve.mjs';
import { launch, problem } from './chromium.mjs';

const ROOT = path.resolve(JS_ROOT, '..');
const CORPUS = process.env.PLN_CORPUS ?? path.join(ROOT, 'tests', 'corpus');
const args = process.argv.slice(2);
/** @param {string} name */
function option(name) {
  const i = args.indexOf(name);
  if (i < 0) return null;
  const [value] = args.splice(i, 2).slice(1);
  return value;
}
const up = option('--up') ?? (args.length ? null : 'Z');
const [width, height] = (option('--size') ?? '1280x760').split('x').map(Number);
const source = args[0] ?? path.join(CORPUS, 'cad/featuretype.STL');
const out = path.resolve(args[1] ?? path.join(ROOT, 'docs/viewer.png'));

const why = await problem();
if (why) {
  console.error(`screenshot.mjs: ${why}`);
  process.exit(1);
}
let pln = source;
if (!source.toLowerCase().endsWith('.pln')) {
  pln = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 'pln-shot-')), `${path.basename(source)}.pln`);
  execFileSync(path.join(ROOT, '.venv/bin/pln'), ['convert', source, pln], { stdio: ['ignore', 'ignore', 'inherit'] });
}
const name = path.basename(source.toLowerCase().endsWith('.pln') ? source : `${path.basename(source)}.pln`);
const server = await serve({ extra: { [name]: pln } });
const { browser, page, consoleErrors } = await launch({ width, height });
try {
  await page.goto(`${server.url}viewer/?file=../extra/${encodeURIComponent(name)}${up ? `&up=${up}` : ''}`);
  await page.waitForFunction(() => /** @type {any} */ (window).plnViewer !== undefined);
  const stats = await page.evaluate(() => /** @type {any} */ (window).plnViewer.ready);
  await page.screenshot({ path: out });
  console.log(`${out}: ${name}, ${stats.triangles} triangles in ${stats.groups} groups`);
  if (consoleErrors.length) console.error(consoleErrors.join('\n'));
} finally {
  await browser.close();
  await server.close();
}
