// The hand-written loader: instantiate the module (no imports) and wrap its C exports.
// Workers use `Renderer`; the page uses `Core` (its own instance: the core's film and
// the lists of scenes and estimators). The page compiles the module once and hands the
// compiled WebAssembly.Module to every worker.

const SETUP_ERRORS = { 1: 'unknown scene', 2: 'unknown estimator', 3: 'bad resolution', 4: 'the scene failed to build' };
const RENDER_ERRORS = { 1: 'not set up', 2: 'pixel or path range out of bounds' };

export async function compileModule(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`fetching ${url}: HTTP ${response.status}`);
  return WebAssembly.compile(await response.arrayBuffer());
}

function utf8(x, ptr, len) {
  return new TextDecoder().decode(new Uint8Array(x.memory.buffer, ptr, len));
}

export class Renderer {
  constructor(module) {
    this.instance = new WebAssembly.Instance(module, {});
    this.x = this.instance.exports;
  }
  // seed: BigInt (u64).
  setup(scene, estimator, width, height, maxDepth, seed) {
    const hi = Number((seed >> 32n) & 0xffffffffn);
    const lo = Number(seed & 0xffffffffn);
    const rc = this.x.ember_setup(scene, estimator, width, height, maxDepth, hi, lo);
    if (rc !== 0) throw new Error(`ember_setup: ${SETUP_ERRORS[-rc] ?? rc}`);
    this.width = width;
    this.height = height;
    return { lightPaths: this.x.ember_light_paths_per_pass(), triangles: this.x.ember_triangle_count(), splatScale: this.x.ember_splat_scale() };
  }
  // Renders one pass's share; returns copies (safe to transfer) of the camera band
  // (3 × f32 per band pixel) and of the splats (5 × f32 each: x, y, r, g, b; null if none).
  render(pass, p0, p1, l0, l1) {
    const rc = this.x.ember_render(pass, p0, p1, l0, l1);
    if (rc !== 0) throw new Error(`ember_render: ${RENDER_ERRORS[-rc] ?? rc}`);
    const mem = this.x.memory.buffer;
    const camera = new Float32Array(mem, this.x.ember_camera_ptr(), 3 * (p1 - p0)).slice();
    const n = this.x.ember_splat_count();
    const splats = n > 0 ? new Float32Array(mem, this.x.ember_splat_ptr(), 5 * n).slice() : null;
    return { camera, splats, rays: this.x.ember_last_rays() };
  }
}

// The page's instance: the core's film and the module's lists.
export class Core {
  constructor(module) {
    this.x = new WebAssembly.Instance(module, {}).exports;
  }
  scenes() {
    const x = this.x;
    return Array.from({ length: x.ember_scene_count() }, (_, i) => utf8(x, x.ember_scene_name(i), x.ember_scene_name_len(i)));
  }
  // [{ name, supported }] in the core's order (the index is the estimator's id).
  estimators() {
    const x = this.x;
    return Array.from({ length: x.ember_estimator_count() }, (_, i) => ({
      name: utf8(x, x.ember_estimator_name(i), x.ember_estimator_name_len(i)), supported: x.ember_estimator_supported(i) === 1,
    }));
  }
  newFilm(width, height) {
    const rc = this.x.ember_film_new(width, height);
    if (rc !== 0) throw new Error(`ember_film_new: ${SETUP_ERRORS[-rc] ?? rc}`);
    this.pixels = width * height;
  }
  #input(values) {
    const ptr = this.x.ember_film_input(values.length);
    new Float32Array(this.x.memory.buffer, ptr, values.length).set(values);
  }
  // Stage a worker's camera band (pixels first..) and, after all bands, its splats.
  camera(first, values) {
    this.#input(values);
    this.x.ember_film_camera(first);
  }
  splats(values) {
    this.#input(values);
    this.x.ember_film_splats();
  }
  endPass(scale) {
    this.x.ember_film_end_pass(scale);
  }
  // The mean image (3 × f32 per pixel, row 0 at the top), a copy.
  image() {
    const ptr = this.x.ember_film_image();
    return new Float32Array(this.x.memory.buffer, ptr, 3 * this.pixels).slice();
  }
  passes() {
    return this.x.ember_film_passes();
  }
  discarded() {
    return this.x.ember_film_discarded();
  }
}
