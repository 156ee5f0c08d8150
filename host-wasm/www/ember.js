// The hand-written loader: instantiate the module (no imports) and wrap its C exports.
// The page and every worker hold one `Instance` each: same scene, same estimator, same
// phases (the core's render protocol; host-wasm/src/lib.rs has the protocol). The page
// compiles the module once and hands the compiled WebAssembly.Module to every worker.

export const PART_FILM = 0;
export const PART_STATE = 1;
const TEXT = { scene: 0, estimator: 1, summary: 2, config: 3, error: 4, phase: 5 };
export const ROLE_WORKER = 0;
export const ROLE_PAGE = 1;
const U64_MAX = (1n << 64n) - 1n;

export async function compileModule(url) {
  const response = await fetch(url);
  if (!response.ok) throw new Error(`fetching ${url}: HTTP ${response.status} (build it with scripts/build-wasm.sh)`);
  return WebAssembly.compile(await response.arrayBuffer());
}

// A decimal seed in 0..2^64-1 as a BigInt, or an error message.
export function parseSeed(text) {
  const s = String(text).trim();
  if (!/^[0-9]+$/.test(s)) return { error: `seed "${s}": a whole number from 0 to ${U64_MAX} is needed` };
  const v = BigInt(s);
  if (v > U64_MAX) return { error: `seed ${s}: above ${U64_MAX}` };
  return { value: v };
}

// An integer in lo..=hi, or an error message naming `name`.
export function parseInteger(name, text, lo, hi) {
  const s = String(text).trim();
  if (!/^[0-9]+$/.test(s) || Number(s) < lo || Number(s) > hi) return { error: `${name} "${s}": a whole number from ${lo} to ${hi} is needed` };
  return { value: Number(s) };
}

export class Instance {
  constructor(module) {
    this.x = new WebAssembly.Instance(module, {}).exports;
  }
  text(what, i = 0) {
    const n = this.x.ember_text(what, i);
    if (n < 0) return null;
    return new TextDecoder().decode(new Uint8Array(this.x.memory.buffer, this.x.ember_text_ptr(), n));
  }
  // Throws with the module's message when an export returned a negative code.
  check(rc, call) {
    if (rc < 0) throw new Error(`${call}: ${this.text(TEXT.error)} (code ${-rc})`);
    return rc;
  }
  scenes() {
    return Array.from({ length: this.x.ember_scene_count() }, (_, i) => this.text(TEXT.scene, i));
  }
  // The core's estimator list, in its order (the index is what setup takes); `compiled`
  // is false for one the module was built without (its cargo features).
  estimators() {
    return Array.from({ length: this.x.ember_estimator_count() }, (_, i) => ({
      name: this.text(TEXT.estimator, i), summary: this.text(TEXT.summary, i), config: this.text(TEXT.config, i),
      compiled: this.x.ember_estimator_compiled(i) === 1,
    }));
  }
  // seed: BigInt (u64); role: ROLE_PAGE (holds the film) or ROLE_WORKER.
  setup(scene, estimator, width, height, maxDepth, seed, role) {
    const hi = Number((seed >> 32n) & 0xffffffffn);
    const lo = Number(seed & 0xffffffffn);
    this.check(this.x.ember_setup(scene, estimator, width, height, maxDepth, hi, lo, role), 'setup');
    this.pixels = width * height;
    return { triangles: this.x.ember_triangle_count() };
  }
  startPass(pass) {
    this.check(this.x.ember_start_pass(pass), 'start pass');
  }
  // The next phase (taken as the current one), or null when the pass is done.
  nextPhase() {
    if (this.check(this.x.ember_next_phase(), 'next phase') === 0) return null;
    const pass = this.x.ember_phase_pass();
    return {
      id: this.x.ember_phase_id(), pass: pass < 0 ? null : pass, items: this.x.ember_phase_items(),
      chunks: this.x.ember_phase_chunks(), samples: this.x.ember_phase_samples() === 1, name: this.text(TEXT.phase),
    };
  }
  #part(p) {
    const ptr = this.x.ember_part_ptr(p), len = this.x.ember_part_len(p);
    return new Uint8Array(this.x.memory.buffer, ptr, len).slice().buffer;
  }
  // Map chunk `chunk` of the current phase: its two parts as fresh (transferable) buffers.
  map(chunk) {
    this.check(this.x.ember_map(chunk), `map chunk ${chunk}`);
    return { film: this.#part(PART_FILM), state: this.#part(PART_STATE), rays: this.x.ember_map_rays() };
  }
  // Hand part `part` (PART_FILM or PART_STATE) of chunk `chunk` to this instance.
  receive(chunk, part, buffer) {
    const bytes = new Uint8Array(buffer);
    const ptr = this.x.ember_input(bytes.length);
    new Uint8Array(this.x.memory.buffer, ptr, bytes.length).set(bytes);
    this.check(this.x.ember_receive(chunk, part), `receive chunk ${chunk}`);
  }
  // Reduce the current phase; true when it committed a pass to the film.
  reduce() {
    return this.check(this.x.ember_reduce(), 'reduce') === 1;
  }
  // The film's mean (3 × f32 per pixel, row 0 at the top), a copy.
  image() {
    // The call may grow the memory, which detaches the old buffer: read it after.
    const ptr = this.x.ember_image();
    return new Float32Array(this.x.memory.buffer, ptr, 3 * this.pixels).slice();
  }
  passes() {
    return this.x.ember_film_passes();
  }
  discarded() {
    return this.x.ember_film_discarded();
  }
}

// Two phases agree when every number the protocol depends on agrees.
export function samePhase(a, b) {
  return !!a && !!b && a.id === b.id && a.pass === b.pass && a.items === b.items && a.chunks === b.chunks;
}
