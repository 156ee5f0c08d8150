// One Web Worker: its own instance of the module, the same scene and estimator as the
// page's. It maps the chunks it is handed and reduces every phase from the state parts
// the page forwards, so its copy of the estimator's state (light-vertex caches, SPCBPT's
// Γ and Q) stays the page's. After every 'pass' and 'reduce' it reports the phase it
// took, which the page checks against its own.
import { Instance, PART_STATE, ROLE_WORKER, samePhase } from './ember.js';

let instance = null;
let phase = null;

function reply(m, data, transfer = []) {
  self.postMessage({ id: m.id, seq: m.seq, ...data }, transfer);
}

self.onmessage = (event) => {
  const m = event.data;
  try {
    if (m.type === 'setup') {
      instance = new Instance(m.module);
      const info = instance.setup(m.scene, m.estimator, m.width, m.height, m.maxDepth, BigInt(m.seed), ROLE_WORKER);
      reply(m, { type: 'ready', ...info });
    } else if (m.type === 'pass') {
      instance.startPass(m.pass);
      phase = instance.nextPhase();
      reply(m, { type: 'phase', phase });
    } else if (m.type === 'map') {
      if (!samePhase(phase, m.phase)) throw new Error(`worker ${m.id} is at phase ${JSON.stringify(phase)}, asked to map ${JSON.stringify(m.phase)}`);
      const t0 = performance.now();
      const r = instance.map(m.chunk);
      reply(m, { type: 'mapped', chunk: m.chunk, ms: performance.now() - t0, ...r }, [r.film, r.state]);
    } else if (m.type === 'reduce') {
      m.states.forEach((s, c) => { if (s) instance.receive(c, PART_STATE, s); });
      instance.reduce();
      phase = instance.nextPhase();
      reply(m, { type: 'phase', phase });
    }
  } catch (e) {
    reply(m, { type: 'error', message: String(e && e.message || e) });
  }
};
