// The page: compiles the module once, starts one worker per core, hands each a band of
// every pass (pixels for PT/BDPT camera samples, light paths for LT), and feeds the bands
// and then every worker's splats, in worker order, to the core's film in its own module
// instance; tone-maps the film's mean onto the canvas and writes it as PFM. The scene and
// estimator lists come from the module. Random numbers depend on (seed, pixel/path, pass)
// only and the film reduces in index order, so the image does not depend on the number
// of workers at all.
//
// Automation (scripts/test-browser.sh): URL parameters scene, estimator, width, height,
// passes, seed, workers, autostart=1 fill the form and start; window.ember exposes the
// state (passes done, errors, samples/s) and the linear image.
import { Core, compileModule } from './ember.js';

const $ = (id) => document.getElementById(id);
const canvas = $('canvas');
const ctx = canvas.getContext('2d');

const ember = {
  loaded: false, running: false, finished: false, passes: 0, errors: [],
  elapsedMs: 0, samples: 0, rays: 0, samplesPerSecond: 0, workers: 0, discarded: 0,
  width: 0, height: 0, image: null,
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
let core = null;
let scenes = [];
let estimators = [];
let workers = [];
let generation = 0;
const params = new URLSearchParams(location.search);

// The lists from the module, then the form ← URL parameters.
function fillForm() {
  scenes = core.scenes();
  estimators = core.estimators();
  $('scene').replaceChildren(...scenes.map((name, i) => new Option(name, i)));
  $('estimator').replaceChildren(...estimators.map((e, i) => {
    const o = new Option(e.supported ? e.name : `${e.name} (not in the browser yet)`, i);
    o.disabled = !e.supported;
    return o;
  }));
  $('estimator').value = String(estimators.findIndex((e) => e.name === 'bdpt'));
  for (const key of ['scene', 'estimator', 'width', 'height', 'passes', 'seed', 'workers']) {
    if (params.has(key)) $(key).value = params.get(key);
  }
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
    samplesPerSecond: 0, workers: count, width, height, discarded: 0, image: null });
  core.newFilm(width, height);
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
  const samplesPerPass = lightPaths > 0 ? lightPaths : pixels;
  const splatScale = ready[0].splatScale;
  const label = `${scenes[scene]} / ${estimators[estimator].name} / ${width}×${height} / ${count} worker${count > 1 ? 's' : ''} / ${ready[0].triangles} triangles`;

  for (let pass = 0; pass < maxPasses; pass++) {
    const t0 = performance.now();
    const results = await Promise.all(workers.map((w, k) => request(w, {
      type: 'render', id: k, pass, p0: cut(pixels, k), p1: cut(pixels, k + 1),
      l0: cut(lightPaths, k), l1: cut(lightPaths, k + 1),
    })));
    if (gen !== generation) return;
    // The core's film: every band's camera values, then the splats in worker order
    // (pixel or light-path order), whatever order the workers finished in.
    for (const r of results) {
      core.camera(r.p0, r.camera);
      ember.rays += r.rays;
    }
    for (const r of results) if (r.splats) core.splats(r.splats);
    core.endPass(splatScale);
    ember.image = core.image();
    ember.discarded = core.discarded();
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

// The mean over passes as f32, row 0 at the top (the core film's to_rgb_f32).
function linearImage() {
  return ember.image ? ember.image.slice() : new Float32Array(0);
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
  if (!ember.image) return;
  const { width, height } = ember;
  const scale = Math.pow(2, Number($('exposure').value));
  const image = ctx.createImageData(width, height);
  const mean = ember.image, px = image.data;
  for (let i = 0, j = 0; i < width * height; i++, j += 3) {
    for (let c = 0; c < 3; c++) px[4 * i + c] = Math.round(255 * srgb(Math.min(Math.max(mean[j + c] * scale, 0), 1)));
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
  a.download = `ember-${scenes[Number($('scene').value)]}-${estimators[Number($('estimator').value)].name}-${ember.passes}pass.pfm`;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
};

try {
  module = await compileModule('ember_wasm.wasm');
  core = new Core(module);
  fillForm();
  ember.loaded = true;
  $('status').textContent = 'module loaded';
  if (params.get('autostart') === '1') start().catch((e) => fail(String(e && e.stack || e)));
} catch (e) {
  fail(`loading the module: ${e}`);
}
