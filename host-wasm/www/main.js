// The page: compiles the module once, starts one worker per core, hands each a band of
// every pass (pixels for PT/BDPT camera samples, light paths for LT), sums the bands and
// every worker's splat film into one f64 film, tone-maps it onto the canvas, and writes
// the linear mean as PFM. Random numbers depend on (seed, pixel/path, pass) only, so the
// image does not depend on the number of workers (up to f64 summation order).
//
// Automation (scripts/test-browser.sh): URL parameters scene, estimator, width, height,
// passes, seed, workers, autostart=1 fill the form and start; window.ember exposes the
// state (passes done, errors, samples/s) and the linear image.
import { SCENES, ESTIMATORS, compileModule } from './ember.js';

const $ = (id) => document.getElementById(id);
const canvas = $('canvas');
const ctx = canvas.getContext('2d');

const ember = {
  loaded: false, running: false, finished: false, passes: 0, errors: [],
  elapsedMs: 0, samples: 0, rays: 0, samplesPerSecond: 0, workers: 0, discarded: 0,
  width: 0, height: 0, sum: null,
  linear: () => linearImage(),
  pfm: () => pfmBytes(),
};
window.ember = ember;

function fail(message) {
  ember.errors.push(message);
  $('error').textContent = ember.errors.join('\n');
  console.error(message);
  stop();
}

let module = null;
let workers = [];
let generation = 0;

// Form ← URL parameters.
const params = new URLSearchParams(location.search);
for (const key of ['scene', 'estimator', 'width', 'height', 'passes', 'seed', 'workers']) {
  if (params.has(key)) $(key).value = params.get(key);
}

function stop() {
  generation++;
  for (const w of workers) w.terminate();
  workers = [];
  ember.running = false;
}

function request(worker, message) {
  return new Promise((resolve, reject) => {
    worker.onmessage = (e) => (e.data.type === 'error' ? reject(new Error(e.data.message)) : resolve(e.data));
    worker.onerror = (e) => reject(new Error(`worker error: ${e.message || 'failed to load'}`));
    worker.postMessage(message);
  });
}

async function start() {
  stop();
  const gen = generation;
  const scene = Number($('scene').value), estimator = Number($('estimator').value);
  const width = Number($('width').value), height = Number($('height').value);
  const maxPasses = Number($('passes').value) || Infinity;
  const seed = $('seed').value || '0';
  const count = Number($('workers').value) || Math.min(navigator.hardwareConcurrency || 1, 16);
  Object.assign(ember, { running: true, finished: false, passes: 0, elapsedMs: 0, samples: 0, rays: 0,
    samplesPerSecond: 0, workers: count, width, height, discarded: 0, sum: new Float64Array(3 * width * height) });
  canvas.width = width;
  canvas.height = height;
  canvas.style.width = `${Math.min(512, 4 * width)}px`;

  workers = Array.from({ length: count }, () => new Worker('worker.js', { type: 'module' }));
  const setup = { type: 'setup', module, scene, estimator, width, height, maxDepth: -1, seed };
  const ready = await Promise.all(workers.map((w, id) => request(w, { ...setup, id })));
  if (gen !== generation) return;
  const lightPaths = ready[0].lightPaths;
  const pixels = width * height;
  const cut = (total, k) => Math.floor((total * k) / count);
  const samplesPerPass = estimator === 1 ? lightPaths : pixels;
  const label = `${SCENES[scene]} / ${ESTIMATORS[estimator]} / ${width}×${height} / ${count} worker${count > 1 ? 's' : ''} / ${ready[0].triangles} triangles`;

  for (let pass = 0; pass < maxPasses; pass++) {
    const t0 = performance.now();
    const results = await Promise.all(workers.map((w, k) => request(w, {
      type: 'render', id: k, pass, p0: cut(pixels, k), p1: cut(pixels, k + 1),
      l0: cut(lightPaths, k), l1: cut(lightPaths, k + 1),
    })));
    if (gen !== generation) return;
    // Sum in worker order, whatever order they finished in.
    const sum = ember.sum;
    for (const r of results) {
      const base = 3 * r.p0;
      for (let i = 0; i < r.camera.length; i++) sum[base + i] += r.camera[i];
      if (r.splats) for (let i = 0; i < sum.length; i++) sum[i] += r.splats[i];
      ember.rays += r.rays;
    }
    ember.discarded = results.reduce((a, r) => a + r.discarded, 0);
    ember.elapsedMs += performance.now() - t0;
    ember.passes = pass + 1;
    ember.samples += samplesPerPass;
    ember.samplesPerSecond = ember.samples / (ember.elapsedMs / 1000);
    draw();
    $('status').textContent = `${label}\npass ${ember.passes}  elapsed ${(ember.elapsedMs / 1000).toFixed(2)} s  ` +
      `${(ember.samplesPerSecond / 1e3).toFixed(1)} k samples/s  ${(ember.rays / ember.elapsedMs / 1e3).toFixed(2)} M rays/s`;
  }
  ember.running = false;
  ember.finished = true;
}

// The mean over passes as f32, row 0 at the top (what the CLI's Film::to_rgb_f32 gives).
function linearImage() {
  const out = new Float32Array(ember.sum ? ember.sum.length : 0);
  const inv = ember.passes > 0 ? 1 / ember.passes : 0;
  for (let i = 0; i < out.length; i++) out[i] = ember.sum[i] * inv;
  return out;
}

// Portable Float Map: "PF\n<w> <h>\n-1.0\n" (negative scale: little-endian), then RGB f32
// rows from the bottom of the image to the top.
function pfmBytes() {
  const { width, height } = ember;
  const img = linearImage();
  const header = new TextEncoder().encode(`PF\n${width} ${height}\n-1.0\n`);
  const bytes = new Uint8Array(header.length + 12 * width * height);
  bytes.set(header);
  const view = new DataView(bytes.buffer, header.length);
  let o = 0;
  for (let y = height - 1; y >= 0; y--) {
    for (let i = 3 * y * width; i < 3 * (y + 1) * width; i++, o += 4) view.setFloat32(o, img[i], true);
  }
  return bytes;
}

const srgb = (v) => (v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055);

function draw() {
  if (!ember.sum) return;
  const { width, height } = ember;
  const scale = Math.pow(2, Number($('exposure').value)) / Math.max(ember.passes, 1);
  const image = ctx.createImageData(width, height);
  const sum = ember.sum, px = image.data;
  for (let i = 0, j = 0; i < width * height; i++, j += 3) {
    for (let c = 0; c < 3; c++) px[4 * i + c] = Math.round(255 * srgb(Math.min(Math.max(sum[j + c] * scale, 0), 1)));
    px[4 * i + 3] = 255;
  }
  ctx.putImageData(image, 0, 0);
}

$('exposure').oninput = () => { $('exposure-value').textContent = $('exposure').value; draw(); };
$('start').onclick = () => start().catch((e) => fail(String(e && e.stack || e)));
$('stop').onclick = () => stop();
$('download').onclick = () => {
  if (!ember.passes) return;
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([pfmBytes()], { type: 'application/octet-stream' }));
  a.download = `ember-${SCENES[Number($('scene').value)]}-${ESTIMATORS[Number($('estimator').value)]}-${ember.passes}pass.pfm`;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
};

try {
  module = await compileModule('ember_wasm.wasm');
  ember.loaded = true;
  $('status').textContent = 'module loaded';
  if (params.get('autostart') === '1') start().catch((e) => fail(String(e && e.stack || e)));
} catch (e) {
  fail(`loading the module: ${e}`);
}
