/**
 * The .pln viewer (index.html): open or drop a file, or name one with ?file=URL; see it shaded,
 * each part group in its own colour unless the file colours it (cOLR); orbit; read the file's
 * header, counts, groups and bytes per chunk type in the side panel.
 *
 * ?up=Y or ?up=Z overrides the file's up axis (the panel's selector).
 *
 * For tests: window.plnViewer = {ready, stats, load(source), renderer, scene, camera, controls}.
 * `ready` is a promise settled by the first load (the ?file= one; with no ?file= it resolves at
 * once with null): resolved with the stats once the model is drawn, rejected with the error.
 * `stats` holds the panel's values as numbers and strings (null before a file is loaded).
 */
import * as THREE from 'three';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { PLNLoader } from '../three/PLNLoader.mjs';

const CODINGS = ['float32', 'float64', 'quantized', 'predicted'];
const UNITS = ['unspecified', 'metre', 'centimetre', 'millimetre', 'micrometre', 'kilometre', 'inch', 'foot'];
const BACKGROUND = 0x1e2228;

const view = /** @type {HTMLElement} */ (document.getElementById('view'));
const drop = /** @type {HTMLElement} */ (document.getElementById('drop'));
const errorBox = /** @type {HTMLElement} */ (document.getElementById('error'));
const upSelect = /** @type {HTMLSelectElement} */ (document.getElementById('up'));

const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
renderer.setPixelRatio(Math.min(window.devicePixelRatio, 2));
view.appendChild(renderer.domElement);

const scene = new THREE.Scene();
scene.background = new THREE.Color(BACKGROUND);
const camera = new THREE.PerspectiveCamera(40, 1, 0.01, 1000);
scene.add(camera);
scene.add(new THREE.HemisphereLight(0xffffff, 0x5a5f66, 1.6));
const headlight = new THREE.DirectionalLight(0xffffff, 1.8);
headlight.position.set(0.4, 0.8, 1); // over the viewer's shoulder, moving with the camera
camera.add(headlight);
camera.add(headlight.target);

const controls = new OrbitControls(camera, renderer.domElement);
controls.addEventListener('change', render);

/** The file's group, under a holder that turns it to +y up. */
const holder = new THREE.Group();
scene.add(holder);
/** @type {THREE.Group | null} */
let model = null;

function render() { renderer.render(scene, camera); }

function resize() {
  const w = Math.max(1, view.clientWidth);
  const h = Math.max(1, view.clientHeight);
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  render();
}
new ResizeObserver(resize).observe(view);

/** The i-th of a sequence of distinct colours (golden-angle hues). @param {number} i */
function partColour(i) {
  return new THREE.Color().setHSL((0.08 + i * 0.618034) % 1, 0.55, 0.58, THREE.SRGBColorSpace);
}

/** (x, y, z) → (x, z, −y) for a Z-up file (spec §10.3), none for Y. */
function applyUp() {
  const fileUp = model?.userData.upAxis ?? null;
  const up = upSelect.value === 'auto' ? (fileUp ?? 'Y') : upSelect.value;
  holder.rotation.set(up === 'Z' ? -Math.PI / 2 : 0, 0, 0);
  holder.updateMatrixWorld(true);
  if (stats) stats.view = up;
  fit();
}
upSelect.addEventListener('change', applyUp);

/** Camera on the bounding box: the whole model in view from above and to the front right. */
function fit() {
  if (!model) return render();
  const box = new THREE.Box3().setFromObject(holder, true);
  if (box.isEmpty()) return render();
  const centre = box.getCenter(new THREE.Vector3());
  const radius = Math.max(box.getSize(new THREE.Vector3()).length() / 2, 1e-9);
  const fov = THREE.MathUtils.degToRad(camera.fov);
  const dist = radius / Math.sin(Math.min(fov, fov * camera.aspect) / 2) * 1.05;
  const dir = new THREE.Vector3(1, 0.75, 1.35).normalize();
  camera.position.copy(centre).addScaledVector(dir, dist);
  camera.near = dist / 100;
  camera.far = dist * 100;
  camera.updateProjectionMatrix();
  controls.target.copy(centre);
  controls.update();
  render();
}

/** @param {number} n */
const int = (n) => n.toLocaleString('en-US');
/** @param {number} x */
const num = (x) => (Number.isNaN(x) ? 'none' : x === 0 ? '0' : Math.abs(x) >= 1e-3 && Math.abs(x) < 1e6 ? String(+x.toPrecision(6)) : x.toExponential(3));

/** @type {any} */
let stats = null;

/**
 * @param {THREE.Group} root the loader's group
 * @param {string} name @param {number} size
 */
function statsOf(root, name, size) {
  const { header, chunks, records, groups, file, upAxis } = root.userData;
  let vertices = 0;
  root.traverse((o) => { if (/** @type {THREE.Mesh} */ (o).isMesh) vertices += /** @type {THREE.Mesh} */ (o).geometry.getAttribute('position').count; });
  /** @type {Record<string, {chunks: number, bytes: number}>} */
  const chunkBytes = {};
  for (const c of chunks) {
    const e = (chunkBytes[c.type] ??= { chunks: 0, bytes: 0 });
    e.chunks += 1;
    e.bytes += c.size; // head (8 bytes, or 5 to 9 with a version 5 varint length), payload, CRC
  }
  const diag = header.bbox ? Math.hypot(...header.bbox[1].map((/** @type {number} */ v, /** @type {number} */ i) => v - header.bbox[0][i])) : NaN;
  return {
    name,
    size,
    version: header.version.join('.'),
    coding: CODINGS[header.coding] ?? String(header.coding),
    bits: header.coding >= 2 ? header.bits : null,
    lossy: header.lossy,
    tolerance: header.tolerance,
    errorBound: header.error_bound,
    diagonal: diag,
    units: UNITS[header.units] ?? String(header.units),
    upAxis: upAxis ?? null,
    view: 'Y',
    bbox: header.bbox,
    planes: file.planes.length / 3,
    objects: file.objects.length,
    groups: groups.length,
    triangles: groups.reduce((/** @type {number} */ s, /** @type {any} */ g) => s + g.triangles, 0),
    vertices,
    groupTable: groups.map((/** @type {any} */ g) => ({ index: g.index, kind: g.kind, kindName: g.kindName, references: g.references, triangles: g.triangles, source: g.source })),
    chunkBytes,
    records,
  };
}

/** @param {any} s @param {Map<number, string>} swatches */
function showStats(s, swatches) {
  /** @type {Record<string, string>} */
  const text = {
    name: s.name,
    size: `${int(s.size)} bytes`,
    version: s.version,
    coding: s.bits ? `${s.coding} (${s.bits.join(', ')} bits)` : s.coding,
    lossy: s.lossy ? 'yes' : 'no',
    tolerance: Number.isNaN(s.tolerance) ? 'none' : `${num(s.tolerance)} of the diagonal`,
    errorBound: Number.isNaN(s.errorBound) ? 'not measured' : `${num(s.errorBound)} of the diagonal`
      + (Number.isNaN(s.diagonal) ? '' : ` (${num(s.errorBound * s.diagonal)})`),
    units: s.units,
    upAxis: s.upAxis ?? 'not given',
    bboxMin: s.bbox ? s.bbox[0].map(num).join(', ') : 'not given',
    bboxMax: s.bbox ? s.bbox[1].map(num).join(', ') : 'not given',
    planes: int(s.planes),
    objects: int(s.objects),
    groups: int(s.groups),
    triangles: int(s.triangles),
    vertices: int(s.vertices),
  };
  for (const el of document.querySelectorAll('[data-stat]')) {
    const key = /** @type {string} */ (/** @type {HTMLElement} */ (el).dataset.stat);
    el.textContent = text[key] ?? '–';
  }
  const gBody = /** @type {HTMLElement} */ (document.querySelector('#groups tbody'));
  gBody.replaceChildren(...s.groupTable.map((/** @type {any} */ g) => row([
    swatches.has(g.index) ? `<span class="swatch" style="background:${swatches.get(g.index)}"></span>${g.index}` : String(g.index),
    g.source === null || g.source === undefined ? `${g.kindName} (${g.kind})` : `${g.kindName} of ${g.source} (${g.kind})`, int(g.references), int(g.triangles)], [false, false, true, true], true)));
  const cBody = /** @type {HTMLElement} */ (document.querySelector('#chunks tbody'));
  const entries = Object.entries(s.chunkBytes).sort((a, b) => b[1].bytes - a[1].bytes);
  cBody.replaceChildren(...entries.map(([type, e]) => row([type, int(e.chunks), int(e.bytes), `${(100 * e.bytes / s.size).toFixed(1)} %`],
    [false, true, true, true])));
  // version 6: the records inside the body segments, by raw (decompressed) bytes
  const raw = s.records.reduce((/** @type {number} */ n, /** @type {any} */ r) => n + r.bytes, 0);
  /** @type {HTMLElement} */ (document.querySelector('#records-wrap')).hidden = s.records.length === 0;
  const rBody = /** @type {HTMLElement} */ (document.querySelector('#records tbody'));
  rBody.replaceChildren(...[...s.records].sort((a, b) => b.bytes - a.bytes).map((/** @type {any} */ r) => row(
    [r.type, int(r.records), int(r.bytes), `${(100 * r.bytes / raw).toFixed(1)} %`], [false, true, true, true])));
}

/** @param {string[]} cells @param {boolean[]} numeric @param {boolean} [html] */
function row(cells, numeric, html = false) {
  const tr = document.createElement('tr');
  cells.forEach((c, i) => {
    const td = document.createElement('td');
    if (numeric[i]) td.className = 'n';
    if (html && i === 0) td.innerHTML = c; else td.textContent = c;
    tr.appendChild(td);
  });
  return tr;
}

/**
 * Shows a file. @param {ArrayBuffer} buffer @param {string} name
 */
function show(buffer, name) {
  const root = new PLNLoader().parse(buffer);
  if (model) {
    holder.remove(model);
    model.traverse((o) => {
      const m = /** @type {THREE.Mesh} */ (o);
      if (m.isMesh) { m.geometry.dispose(); /** @type {THREE.Material} */ (m.material).dispose(); }
    });
  }
  model = root;
  holder.add(root);
  /** @type {Map<number, string>} */
  const swatches = new Map();
  let part = 0;
  root.traverse((o) => {
    const m = /** @type {THREE.Mesh} */ (o);
    if (!m.isMesh) return;
    const mat = /** @type {THREE.MeshStandardMaterial} */ (m.material);
    if (!mat.vertexColors) {
      mat.color.copy(partColour(part++));
      swatches.set(m.userData.groupIndex, `#${mat.color.getHexString(THREE.SRGBColorSpace)}`);
    } else swatches.set(m.userData.groupIndex, 'linear-gradient(90deg,#e44,#4c4,#48f)');
  });
  stats = statsOf(root, name, buffer.byteLength);
  api.stats = stats;
  showStats(stats, swatches);
  errorBox.textContent = '';
  drop.classList.add('hidden');
  document.title = `${name} – .pln viewer`;
  applyUp();
  return stats;
}

/** @param {unknown} err */
function showError(err) {
  const e = /** @type {any} */ (err);
  errorBox.textContent = e && e.code ? `Not a valid .pln file: ${e.code}${e.message ? ` (${e.message})` : ''}` : String(e);
}

/**
 * Loads a File, a URL or an ArrayBuffer; resolves with the stats once drawn.
 * @param {File | string | ArrayBuffer} source @param {string} [name]
 */
async function load(source, name) {
  try {
    let buffer;
    if (typeof source === 'string') {
      const url = new URL(source, window.location.href);
      const response = await fetch(url);
      if (!response.ok) throw new Error(`${url}: HTTP ${response.status}`);
      buffer = await response.arrayBuffer();
      name ??= decodeURIComponent(url.pathname.split('/').pop() || url.href);
    } else if (source instanceof ArrayBuffer) {
      buffer = source;
    } else {
      buffer = await source.arrayBuffer();
      name ??= source.name;
    }
    const s = show(buffer, name ?? 'file.pln');
    await new Promise((resolve) => requestAnimationFrame(() => requestAnimationFrame(resolve)));
    return s;
  } catch (err) {
    showError(err);
    throw err;
  }
}

const openInput = /** @type {HTMLInputElement} */ (document.getElementById('open'));
openInput.addEventListener('change', () => {
  const f = openInput.files?.[0];
  if (f) load(f).catch(() => {});
});
window.addEventListener('dragover', (e) => { e.preventDefault(); document.body.classList.add('dragging'); });
window.addEventListener('dragleave', (e) => { if (!e.relatedTarget) document.body.classList.remove('dragging'); });
window.addEventListener('drop', (e) => {
  e.preventDefault();
  document.body.classList.remove('dragging');
  const f = e.dataTransfer?.files?.[0];
  if (f) load(f).catch(() => {});
});

const api = {
  /** @type {Promise<any>} */
  ready: Promise.resolve(null),
  /** @type {any} */
  stats: null,
  load,
  renderer,
  scene,
  camera,
  controls,
};
/** @type {any} */ (window).plnViewer = api;
resize();
const params = new URLSearchParams(window.location.search);
if (params.get('up') === 'Y' || params.get('up') === 'Z') upSelect.value = /** @type {string} */ (params.get('up'));
const fileParam = params.get('file');
if (fileParam) api.ready = load(fileParam);
