// One Web Worker: its own instance of the module, rendering the band it is sent.
import { Renderer } from './ember.js';

let renderer = null;

self.onmessage = (event) => {
  const m = event.data;
  try {
    if (m.type === 'setup') {
      renderer = new Renderer(m.module);
      const info = renderer.setup(m.scene, m.estimator, m.width, m.height, m.maxDepth, BigInt(m.seed));
      self.postMessage({ type: 'ready', id: m.id, ...info });
    } else if (m.type === 'render') {
      const t0 = performance.now();
      const r = renderer.render(m.pass, m.p0, m.p1, m.l0, m.l1);
      const ms = performance.now() - t0;
      const transfer = [r.camera.buffer];
      if (r.splats) transfer.push(r.splats.buffer);
      self.postMessage({ type: 'done', id: m.id, pass: m.pass, p0: m.p0, ms, ...r }, transfer);
    }
  } catch (e) {
    self.postMessage({ type: 'error', id: m.id, message: String(e && e.stack || e) });
  }
};
