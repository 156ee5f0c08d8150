// The hand-written loader: instantiate the module (no imports) and wrap its C exports.
// Used by worker.js; the page itself only compiles the module once and hands the
// compiled WebAssembly.Module to every worker.

export const SCENES = ['cornell-box', 'glass-spheres'];
export const ESTIMATORS = ['pt', 'lt', 'bdpt'];

const SETUP_ERRORS = { 1: 'unknown scene', 2: 'unknown estimator', 3: 'bad resolution', 4: 'the scene failed to build' };
const RENDER_ERRORS = { 1: 'not set up', 2: 'pixel or path range out of bounds' };

export async function compileModule(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`fetching ${url}: HTTP ${response.status}`);
  return WebAssembly.compile(await response.arrayBuffer());
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
    return { lightPaths: this.x.ember_light_paths_per_pass(), triangles: this.x.ember_triangle_count() };
  }
  // Renders one pass's share; returns copies (safe to transfer) of the camera band
  // (3 × f32 per band pixel) and of the splat film (3 × f64 per pixel, or null if empty).
  render(pass, p0, p1, l0, l1) {
    const rc = this.x.ember_render(pass, p0, p1, l0, l1);
    if (rc !== 0) throw new Error(`ember_render: ${RENDER_ERRORS[-rc] ?? rc}`);
    const mem = this.x.memory.buffer;
    const camera = new Float32Array(mem, this.x.ember_camera_ptr(), 3 * (p1 - p0)).slice();
    const splats = this.x.ember_splat_count() > 0
      ? new Float64Array(mem, this.x.ember_splat_ptr(), 3 * this.width * this.height).slice()
      : null;
    return { camera, splats, rays: this.x.ember_last_rays(), discarded: this.x.ember_discarded() };
  }
}
