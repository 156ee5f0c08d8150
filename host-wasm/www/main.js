// The page: compiles the module once, starts the workers, and drives the core's render
// protocol (host-wasm/src/lib.rs): its own instance (which holds the film) walks the
// estimator's phases; for each phase it hands the chunks to the workers as they come
// free, receives both parts of every chunk's output, reduces, and forwards every chunk's
// state part to every worker, which reduces too, keeping its copy of the estimator's
// state. Every phase order, estimator and film is the core's; the page only moves bytes.
// Random numbers depend on (seed, index, pass) and reductions take chunks in index
// order, so the image does not depend on the number of workers or on which maps what.
//
// Automation (scripts/test-browser.sh): URL parameters scene, estimator (index or name),
// width, height, passes, seed, workers, autostart=1 fill the form and start;
// fault=drop-light-chunk makes the page drop one chunk of the first light-path phase
// (the browser test checks that this stops the render with an error). window.ember
// exposes the state (passes done, errors, samples/s, time per phase) and the image.
import { Instance, PART_FILM, PART_STATE, ROLE_PAGE, compileModule, parseInteger, parseSeed, samePhase } from './ember.js';

const $ = (id) => document.getElementById(id);
const canvas = $('canvas');
const ctx = canvas.getContext('2d');

const ember = {
  loaded: false, running: false, finished: false, passes: 0, errors: [],
  elapsedMs: 0, startupMs: 0, setupMs: 0, samples: 0, rays: 0, samplesPerSecond: 0, workers: 0, discarded: 0,
  width: 0, height: 0, image: null, estimator: null, phaseMs: {},
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
let core = null; // the page's instance: the lists, before any render
let scenes = [];
let estimators = [];
let pool = [];
let generation = 0;
const params = new URLSearchParams(location.search);

// A worker with numbered requests: each message gets one reply (or an error).
class Worker_ {
  constructor(id) {
    this.id = id;
    this.seq = 0;
    this.pending = new Map();
    this.w = new Worker('worker.js', { type: 'module' });
    this.w.onmessage = (e) => {
      const p = this.pending.get(e.data.seq);
      if (!p) return;
      this.pending.delete(e.data.seq);
      if (e.data.type === 'error') p.reject(new Error(`worker ${this.id}: ${e.data.message}`));
      else p.resolve(e.data);
    };
    this.w.onerror = (e) => {
      for (const p of this.pending.values()) p.reject(new Error(`worker ${this.id}: ${e.message || 'failed to load'}`));
      this.pending.clear();
    };
  }
  request(message, transfer = []) {
    const seq = ++this.seq;
    return new Promise((resolve, reject) => {
      this.pending.set(seq, { resolve, reject });
      this.w.postMessage({ ...message, id: this.id, seq }, transfer);
    });
  }
  terminate() {
    this.w.terminate();
  }
}

function fillForm() {
  scenes = core.scenes();
  estimators = core.estimators();
  $('scene').replaceChildren(...scenes.map((name, i) => new Option(name, i)));
  $('estimator').replaceChildren(...estimators.map((e, i) => {
    const option = new Option(e.compiled ? e.name : `${e.name} (not in this module)`, i);
    option.disabled = !e.compiled;
    return option;
  }));
  const bdpt = estimators.findIndex((e) => e.name === 'bdpt' && e.compiled);
  $('estimator').value = String(bdpt >= 0 ? bdpt : estimators.findIndex((e) => e.name === 'pt'));
  for (const key of ['scene', 'width', 'height', 'passes', 'seed', 'workers']) {
    if (params.has(key)) $(key).value = params.get(key);
  }
  if (params.has('estimator')) {
    const v = params.get('estimator');
    const byName = estimators.findIndex((e) => e.name === v);
    $('estimator').value = String(byName >= 0 ? byName : Number(v));
  }
  describe();
}

// The chosen estimator's summary and default configuration, from the core.
function describe() {
  const e = estimators[Number($('estimator').value)];
  $('about').textContent = e ? `${e.summary}\ndefaults: ${e.config}` : '';
}

function stop() {
  generation++;
  for (const w of pool) w.terminate();
  pool = [];
  ember.running = false;
}

// The form, validated: every problem named, nothing started on a bad value.
function readForm() {
  const problems = [];
  const take = (r) => { if (r.error) problems.push(r.error); return r.value; };
  const cores = Math.min(navigator.hardwareConcurrency || 1, 16);
  const form = {
    scene: Number($('scene').value),
    estimator: Number($('estimator').value),
    width: take(parseInteger('width', $('width').value, 1, 4096)),
    height: take(parseInteger('height', $('height').value, 1, 4096)),
    passes: take(parseInteger('passes', $('passes').value, 0, 1e9)),
    seed: take(parseSeed($('seed').value)),
    workers: take(parseInteger('workers', $('workers').value, 0, 64)),
  };
  if (!(form.estimator >= 0 && form.estimator < estimators.length)) problems.push(`estimator ${$('estimator').value}: not in the core's list`);
  else if (!estimators[form.estimator].compiled) problems.push(`estimator ${estimators[form.estimator].name}: not compiled into this module`);
  if (form.workers === 0) form.workers = cores;
  return { form, problems };
}

function status(text) {
  $('status').textContent = text;
}

async function start() {
  stop();
  ember.errors = [];
  $('error').textContent = '';
  const { form, problems } = readForm();
  if (problems.length) {
    $('error').textContent = problems.join('\n');
    ember.errors.push(...problems);
    return;
  }
  const gen = generation;
  const { scene, estimator, width, height, workers: count } = form;
  const maxPasses = form.passes || Infinity;
  Object.assign(ember, { running: true, finished: false, passes: 0, elapsedMs: 0, startupMs: 0, setupMs: 0, samples: 0, rays: 0,
    samplesPerSecond: 0, workers: count, width, height, discarded: 0, image: null, estimator: estimators[estimator].name, phaseMs: {} });
  canvas.width = width;
  canvas.height = height;
  canvas.style.width = `${Math.min(512, 4 * width)}px`;
  $('progress').max = Number.isFinite(maxPasses) ? maxPasses : 1;
  $('progress').value = 0;

  const t0 = performance.now();
  const page = new Instance(module);
  const { triangles } = page.setup(scene, estimator, width, height, -1, form.seed, ROLE_PAGE);
  pool = Array.from({ length: count }, (_, k) => new Worker_(k));
  const setup = { type: 'setup', module, scene, estimator, width, height, maxDepth: -1, seed: String(form.seed) };
  await Promise.all(pool.map((w) => w.request(setup)));
  if (gen !== generation) return;
  // Starting the workers and building the scene and BVH in each: not rendering.
  ember.startupMs = performance.now() - t0;
  const label = `${scenes[scene]} / ${estimators[estimator].name} / ${width}×${height} / ${count} worker${count > 1 ? 's' : ''} / ${triangles} triangles`;
  let dropped = params.get('fault') !== 'drop-light-chunk';

  for (let pass = 0; pass < maxPasses; pass++) {
    page.startPass(pass);
    let reported = await Promise.all(pool.map((w) => w.request({ type: 'pass', pass })));
    for (let phase = page.nextPhase(); phase; phase = page.nextPhase()) {
      if (gen !== generation) return;
      reported.forEach((r, k) => {
        if (!samePhase(r.phase, phase)) throw new Error(`worker ${k} is out of step: at ${JSON.stringify(r.phase)}, the page at ${JSON.stringify(phase)}`);
      });
      const p0 = performance.now();
      const outputs = await mapPhase(phase, gen, label);
      if (gen !== generation) return;
      if (!dropped && phase.name.includes('light') && phase.chunks > 1) {
        outputs[1] = null; // the injected fault: one worker's light-path chunk lost
        dropped = true;
      }
      const states = outputs.map((o) => (o ? o.state : null));
      outputs.forEach((o, c) => {
        if (!o) return;
        page.receive(c, PART_FILM, o.film);
        page.receive(c, PART_STATE, o.state);
        ember.rays += o.rays;
      });
      // The workers reduce from copies of the state parts (the last one takes the
      // originals) while the page reduces its own.
      const last = pool.length - 1;
      const acks = pool.map((w, k) => w.request({ type: 'reduce', states }, k === last ? states.filter((s) => s) : []));
      const ended = page.reduce();
      reported = await Promise.all(acks);
      const ms = performance.now() - p0;
      const key = phase.pass === null ? `setup: ${phase.name}` : phase.name;
      ember.phaseMs[key] = (ember.phaseMs[key] || 0) + ms;
      if (phase.pass === null) ember.setupMs += ms;
      if (phase.samples) ember.samples += phase.items;
      if (ended) {
        ember.passes = page.passes();
        ember.image = page.image();
        ember.discarded = page.discarded();
        draw();
      }
    }
    ember.elapsedMs = performance.now() - t0;
    // Samples over the time since the workers were ready (the estimator's own setup
    // phases included, as the CLI counts them).
    ember.samplesPerSecond = ember.samples / ((ember.elapsedMs - ember.startupMs) / 1000);
    $('progress').value = Number.isFinite(maxPasses) ? ember.passes : 1;
    const eta = Number.isFinite(maxPasses) ? `  ETA ${((ember.elapsedMs / ember.passes) * (maxPasses - ember.passes) / 1000).toFixed(1)} s` : '';
    status(`${label}\npass ${ember.passes}${Number.isFinite(maxPasses) ? ` of ${maxPasses}` : ''}  elapsed ${(ember.elapsedMs / 1000).toFixed(2)} s` +
      ` (workers ${(ember.startupMs / 1000).toFixed(2)} s, estimator setup ${(ember.setupMs / 1000).toFixed(2)} s)${eta}\n${(ember.samplesPerSecond / 1e3).toFixed(1)} k samples/s  ` +
      `${(ember.rays / (ember.elapsedMs - ember.startupMs) / 1e3).toFixed(2)} M rays/s`);
  }
  ember.running = false;
  ember.finished = true;
}

// Map every chunk of `phase` on the workers, two requests in flight per worker, chunks
// handed out in order as workers come free; the outputs in chunk order.
async function mapPhase(phase, gen, label) {
  const outputs = new Array(phase.chunks);
  let next = 0, done = 0;
  const setupText = phase.pass === null;
  const loop = async (w) => {
    while (next < phase.chunks && gen === generation) {
      const c = next++;
      outputs[c] = await w.request({ type: 'map', chunk: c, phase });
      done++;
      if (setupText) status(`${label}\npreprocessing: ${phase.name}, ${done} of ${phase.chunks} chunks`);
    }
  };
  await Promise.all(pool.flatMap((w) => [loop(w), loop(w)]));
  return outputs;
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
$('estimator').onchange = describe;
$('start').onclick = () => start().catch((e) => fail(String(e && e.message || e)));
$('stop').onclick = () => stop();
$('download').onclick = () => {
  if (!ember.passes) return;
  const a = document.createElement('a');
  a.href = URL.createObjectURL(new Blob([pfmBytes()], { type: 'application/octet-stream' }));
  a.download = `ember-${scenes[Number($('scene').value)]}-${ember.estimator}-${ember.passes}pass.pfm`;
  a.click();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
};

try {
  module = await compileModule('ember_wasm.wasm');
  core = new Instance(module);
  fillForm();
  ember.loaded = true;
  status('module loaded');
  if (params.get('autostart') === '1') start().catch((e) => fail(String(e && e.message || e)));
} catch (e) {
  fail(`loading the module: ${e}`);
}
