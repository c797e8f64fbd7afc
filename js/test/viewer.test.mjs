// The viewer (viewer/index.html) in headless Chromium (Debian's chromium, driven by playwright-core)
// from a node:http static server of js/: it opens corpus parts encoded by `pln convert` with
// ?file=, and a test must see a drawn model (the WebGL canvas's screenshot: more than 5 % of its
// pixels away from the background, many distinct colours) and the panel's counts equal to what
// readPln reports for the same file in Node; two 4.0 golden files (Brotli decoded in the page by
// brotli-dec-wasm's WebAssembly) likewise. Skipped, with the reason, where Chromium or
// playwright-core is missing. About 10 s.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { readPln } from '../src/node.mjs';
import { available, encoded } from '../bench/corpus.mjs';
import { serve } from '../viewer/serve.mjs';
import { problem, launch } from '../viewer/chromium.mjs';
import { decodePng } from '../viewer/png.mjs';
import { file6, header6, segment, record, QUANT6, objectRecord, planesRecord, cubeGroup } from './files.mjs';

const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
const BACKGROUND = [0x1e, 0x22, 0x28]; // viewer.mjs's BACKGROUND
const why = await problem();

/** A corpus part as .pln, or (without planefmt or the corpus) a golden file in its place. */
function part(/** @type {string} */ rel, /** @type {string} */ golden) {
  if (available) return encoded(rel);
  console.log(`# planefmt or the corpus is missing: ${golden} instead of ${rel}`);
  return path.join(ROOT, 'conformance/valid', golden);
}

/** @type {Awaited<ReturnType<typeof serve>>} */
let server;
/** @type {Awaited<ReturnType<typeof launch>>} */
let chrome;
/** @type {Record<string, string>} served under /extra/ */
const extra = {};
let tmp = '';

before(async () => {
  if (why) return;
  extra['box.pln'] = part('cad/box.STL', 'shell_tree_box_v3_4.pln');
  extra['truck.pln'] = part('gltf_scene/CesiumMilkTruck.glb', 'scene_v3_stream.pln');
  extra['up_z.pln'] = path.join(ROOT, 'conformance/valid/cube_meta_up_z.pln');
  extra['brotli.pln'] = path.join(ROOT, 'conformance/valid/brotli_shell_tree_v4_0.pln');
  extra['scene4.pln'] = path.join(ROOT, 'conformance/valid/scene_transforms_v4_0.pln');
  extra['walk.pln'] = path.join(ROOT, 'conformance/valid/shell_walk_sphere_v4_1.pln');
  extra['v5_up_z.pln'] = path.join(ROOT, 'conformance/valid/walk_planeless_v5_0.pln');
  const bad = fs.readFileSync(extra['box.pln']).subarray(0, 100);
  tmp = fs.mkdtempSync(path.join(os.tmpdir(), 'pln-viewer-'));
  extra['truncated.pln'] = path.join(tmp, 'truncated.pln');
  fs.writeFileSync(extra['truncated.pln'], bad);
  // version 6: the object and planes in PHDR's segment (zlib), the group and its colours in a BODY (Brotli)
  extra['v6.pln'] = path.join(tmp, 'v6.pln');
  fs.writeFileSync(extra['v6.pln'], file6(header6(QUANT6), {
    first: segment([...objectRecord('cube'), ...planesRecord()], 1),
    chunks: [{ type: 'BODY', payload: segment([...cubeGroup(), ...record(4, [0, 6, 200, 120, 40, 255])], 2) }],
  }));
  server = await serve({ extra });
  chrome = await launch({ width: 1000, height: 700 });
});

after(async () => {
  await chrome?.browser.close();
  await server?.close();
  if (tmp) fs.rmSync(tmp, { recursive: true, force: true });
});

/** What the panel must show: readPln in Node. @param {string} file */
function expected(file) {
  const bytes = fs.readFileSync(file);
  const f = readPln(bytes);
  return {
    size: bytes.length,
    version: f.version.join('.'),
    planes: f.planes.length / 3,
    objects: f.objects.length,
    groups: f.container.groups.length,
    triangles: f.meshes.reduce((s, m) => s + (m ? m.indices.length / 3 : 0), 0),
    perGroup: f.container.groups.map((/** @type {any} */ g) => [g.refs.length, f.meshes[g.index] ? /** @type {any} */ (f.meshes[g.index]).indices.length / 3 : 0]),
    upAxis: f.metadata.up_axis ?? null,
  };
}

// Every timeout here is a hang guard far above normal: a viewer test takes 0.6 to 1.8 s.
/** Opens the viewer on /extra/NAME and waits for it to have drawn the model. @param {string} name */
async function open(name) {
  const { page } = chrome;
  await page.goto(`${server.url}viewer/?file=../extra/${name}`);
  await page.waitForFunction(() => /** @type {any} */ (window).plnViewer !== undefined, null, { timeout: 20000 });
  return page.evaluate(() => /** @type {any} */ (window).plnViewer.ready);
}

/** The panel's text by data-stat, the groups table's rows. */
async function panel() {
  const { page } = chrome;
  const stat = await page.$$eval('[data-stat]', (els) => Object.fromEntries(els.map((e) => [/** @type {HTMLElement} */ (e).dataset.stat, e.textContent])));
  const rows = await page.$$eval('#groups tbody tr', (trs) => trs.map((tr) => [...tr.querySelectorAll('td')].map((td) => td.textContent)));
  return { stat, rows };
}

const int = (/** @type {string | null | undefined} */ s) => Number(String(s).replace(/,/g, ''));

/** The canvas as the page shows it: share of pixels off the background, distinct colours. */
async function canvasPixels() {
  const png = await chrome.page.locator('#view canvas').screenshot();
  const { width, height, rgba } = decodePng(png);
  let off = 0;
  const colours = new Set();
  for (let i = 0; i < rgba.length; i += 4) {
    const d = Math.max(Math.abs(rgba[i] - BACKGROUND[0]), Math.abs(rgba[i + 1] - BACKGROUND[1]), Math.abs(rgba[i + 2] - BACKGROUND[2]));
    if (d > 6) off++;
    colours.add((rgba[i] << 16) | (rgba[i + 1] << 8) | rgba[i + 2]);
  }
  const corner = [...rgba.subarray(0, 3)];
  return { width, height, off: off / (width * height), colours: colours.size, corner };
}

/** The panel against readPln. @param {string} name */
async function checkPanel(name) {
  const want = expected(extra[name]);
  const { stat, rows } = await panel();
  assert.equal(int(stat.planes), want.planes, 'planes');
  assert.equal(int(stat.objects), want.objects, 'objects');
  assert.equal(int(stat.groups), want.groups, 'groups');
  assert.equal(int(stat.triangles), want.triangles, 'triangles');
  assert.equal(stat.version, want.version, 'version');
  assert.equal(int(stat.size?.replace(' bytes', '')), want.size, 'size');
  assert.equal(rows.length, want.groups, 'a table row per group');
  rows.forEach((r, i) => assert.deepEqual([int(r[2]), int(r[3])], want.perGroup[i], `group ${i}: references, triangles`));
  assert.equal(stat.upAxis, want.upAxis ?? 'not given', 'up axis');
  return want;
}

test('viewer: a corpus CAD part drawn, the panel counts as readPln', { skip: why ?? false, timeout: 60000 }, async (t) => {
  const stats = await open('box.pln');
  const want = await checkPanel('box.pln');
  assert.equal(stats.triangles, want.triangles, 'window.plnViewer.stats');
  const px = await canvasPixels();
  t.diagnostic(`canvas ${px.width}x${px.height}: ${(100 * px.off).toFixed(1)} % drawn, ${px.colours} colours`);
  assert.deepEqual(px.corner.map((c, i) => Math.abs(c - BACKGROUND[i]) <= 6), [true, true, true], `background ${px.corner}`);
  assert.ok(px.off > 0.05, `${(100 * px.off).toFixed(1)} % of the canvas drawn`);
  assert.ok(px.colours > 16, `${px.colours} distinct colours`);
  assert.deepEqual(chrome.consoleErrors, []);
});

test('viewer: a scene of several objects and coloured groups', { skip: why ?? false, timeout: 60000 }, async (t) => {
  const stats = await open('truck.pln');
  const want = await checkPanel('truck.pln');
  assert.ok(want.groups > 1, 'several groups');
  assert.equal(stats.groups, want.groups);
  const px = await canvasPixels();
  t.diagnostic(`canvas ${px.width}x${px.height}: ${(100 * px.off).toFixed(1)} % drawn, ${px.colours} colours`);
  assert.ok(px.off > 0.05, `${(100 * px.off).toFixed(1)} % of the canvas drawn`);
  assert.ok(px.colours > 16, `${px.colours} distinct colours`);
  assert.deepEqual(chrome.consoleErrors, []);
});

test('viewer: up_axis Z turns the model +z up', { skip: why ?? false, timeout: 60000 }, async () => {
  const stats = await open('up_z.pln');
  assert.equal(stats.upAxis, 'Z');
  assert.equal(stats.view, 'Z');
  const rotation = await chrome.page.evaluate(() => {
    const v = /** @type {any} */ (window).plnViewer;
    return v.scene.children.find((/** @type {any} */ o) => o.isGroup).rotation.x;
  });
  assert.ok(Math.abs(rotation + Math.PI / 2) < 1e-12, `rotation ${rotation}`);
  await checkPanel('up_z.pln');
});

test('viewer: version 5.0, the header\'s up axis Z turns the model +z up as mETA\'s does; chunk bytes with varint lengths', { skip: why ?? false, timeout: 60000 }, async (t) => {
  const stats = await open('v5_up_z.pln');
  assert.equal(stats.version, '5.0');
  assert.equal(stats.upAxis, 'Z');
  assert.equal(stats.view, 'Z');
  const rotation = await chrome.page.evaluate(() => {
    const v = /** @type {any} */ (window).plnViewer;
    return v.scene.children.find((/** @type {any} */ o) => o.isGroup).rotation.x;
  });
  assert.ok(Math.abs(rotation + Math.PI / 2) < 1e-12, `rotation ${rotation}`);
  const want = await checkPanel('v5_up_z.pln');
  // the chunks table: every byte after the signature in one row or another (heads of 5 to 9 bytes after PHDR)
  const bytes = await chrome.page.$$eval('#chunks tbody tr', (trs) => trs.map((tr) => /** @type {HTMLElement} */ (tr.querySelectorAll('td')[2]).textContent));
  assert.equal(bytes.reduce((sum, b) => sum + int(b), 0), want.size - 8, `chunk bytes ${bytes}`);
  const px = await canvasPixels();
  t.diagnostic(`v5_up_z.pln: canvas ${px.width}x${px.height}: ${(100 * px.off).toFixed(1)} % drawn, ${px.colours} colours`);
  assert.ok(px.off > 0.05, `${(100 * px.off).toFixed(1)} % of the canvas drawn`);
  assert.deepEqual(chrome.consoleErrors, []);
});

test('viewer: version 6.0, segments in PHDR (zlib) and BODY (Brotli); chunk bytes, and raw bytes per record type', { skip: why ?? false, timeout: 60000 }, async (t) => {
  const stats = await open('v6.pln');
  assert.equal(stats.version, '6.0');
  const want = await checkPanel('v6.pln');
  const cells = (/** @type {string} */ table) => chrome.page.$$eval(`${table} tbody tr`, (trs) => trs.map((tr) => [...tr.querySelectorAll('td')].map((td) => td.textContent)));
  const chunks = await cells('#chunks');
  assert.deepEqual(chunks.map((r) => r[0]).sort(), ['BODY', 'PEND', 'PHDR']);
  assert.equal(chunks.reduce((sum, r) => sum + int(r[2]), 0), want.size - 8, `chunk bytes ${chunks}`);
  assert.equal(await chrome.page.$eval('#records-wrap', (el) => /** @type {HTMLElement} */ (el).hidden), false);
  // each record's tag and length and payload: object 2 + 7 (its name 'cube'), planes 2 + 5, group 2 + 10, colours 2 + 6
  const records = (await cells('#records')).map((r) => [r[0], int(r[1]), int(r[2])]);
  assert.deepEqual(records.sort(), [['GRUP', 1, 12], ['OBJT', 1, 9], ['PLNS', 1, 7], ['cOLR', 1, 8]]);
  const px = await canvasPixels();
  t.diagnostic(`v6.pln: canvas ${px.width}x${px.height}: ${(100 * px.off).toFixed(1)} % drawn, ${px.colours} colours`);
  assert.ok(px.off > 0.05, `${(100 * px.off).toFixed(1)} % of the canvas drawn`);
  assert.deepEqual(chrome.consoleErrors, []);
  // a file before version 6 has no records: the table stays hidden
  await open('v5_up_z.pln');
  assert.equal(await chrome.page.$eval('#records-wrap', (el) => /** @type {HTMLElement} */ (el).hidden), true);
});

test('viewer: version 4.0, Brotli payloads decoded in the page (brotli-dec-wasm), coded transforms, one colour', { skip: why ?? false, timeout: 60000 }, async (t) => {
  for (const name of ['brotli.pln', 'scene4.pln']) {
    const stats = await open(name);
    const want = await checkPanel(name);
    assert.equal(want.version, '4.0');
    assert.equal(stats.triangles, want.triangles, `${name}: window.plnViewer.stats`);
    const px = await canvasPixels();
    t.diagnostic(`${name}: canvas ${px.width}x${px.height}: ${(100 * px.off).toFixed(1)} % drawn, ${px.colours} colours`);
    assert.ok(px.off > 0.05, `${name}: ${(100 * px.off).toFixed(1)} % of the canvas drawn`);
  }
  assert.deepEqual(chrome.consoleErrors, []);
});

test('viewer: version 4.1, a shell walk (kind 9) decoded in the page', { skip: why ?? false, timeout: 60000 }, async (t) => {
  const stats = await open('walk.pln');
  const want = await checkPanel('walk.pln');
  assert.equal(want.version, '4.1');
  assert.equal(stats.triangles, want.triangles);
  assert.equal(stats.groupTable[0].kindName, 'shell walk');
  const px = await canvasPixels();
  t.diagnostic(`walk.pln: canvas ${px.width}x${px.height}: ${(100 * px.off).toFixed(1)} % drawn, ${px.colours} colours`);
  assert.ok(px.off > 0.05, `${(100 * px.off).toFixed(1)} % of the canvas drawn`);
  assert.deepEqual(chrome.consoleErrors, []);
});

test('viewer: an invalid file is refused with its error code', { skip: why ?? false, timeout: 60000 }, async () => {
  const err = await open('truncated.pln').then(() => null, (e) => String(e));
  assert.match(String(err), /TRUNCATED/);
  assert.match(await chrome.page.locator('#error').innerText(), /TRUNCATED/);
  const px = await canvasPixels(); // nothing drawn but the drop hint: the pixel check tells a blank canvas
  assert.ok(px.off < 0.03, `${(100 * px.off).toFixed(1)} % of a blank canvas off the background`);
  chrome.consoleErrors.length = 0;
});

test('viewer: a file opened with the file input', { skip: why ?? false, timeout: 60000 }, async () => {
  const { page } = chrome;
  await page.goto(`${server.url}viewer/`);
  await page.waitForFunction(() => /** @type {any} */ (window).plnViewer !== undefined);
  const golden = path.join(ROOT, 'conformance/valid/scene_hierarchy.pln');
  await page.setInputFiles('#open', golden);
  await page.waitForFunction(() => /** @type {any} */ (window).plnViewer.stats?.name === 'scene_hierarchy.pln', null, { timeout: 20000 });
  extra['scene_hierarchy.pln'] = golden;
  await checkPanel('scene_hierarchy.pln');
  assert.deepEqual(chrome.consoleErrors, []);
});
