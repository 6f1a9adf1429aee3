// A picture over the whole view, zoomed and panned. "Fit" gives it the view's height, centred:
// a snapshot is rendered at the view's vertical field of view, so at fit it lies over the model
// when the view's camera is at the snapshot's (the painting does the same while it renders).
// 1:1 is one image pixel to one screen (device) pixel; the wheel, + and − zoom about the
// pointer (or the middle), a drag or the arrow keys pan, 0 fits, Z is 1:1. Magnified, pixels
// are drawn as squares (image-rendering: pixelated), so that each one can be read.

const STEP = 2;

export class Zoom {
  // `viewport` holds `content`; `output` says the zoom; `changed` is told after each change.
  constructor(viewport, content, { output, changed = () => {} }) {
    Object.assign(this, { viewport, content, output, changed });
    this.w = 0;
    this.h = 0;
    this.mode = 'fit';
    this.s = 1;
    this.tx = 0;
    this.ty = 0;
    this.listen();
    new ResizeObserver(() => { if (this.mode === 'fit') this.fit(); }).observe(viewport);
  }

  // The picture's own size, px; shown at fit.
  size(w, h) {
    if (w === this.w && h === this.h) return;
    this.w = w;
    this.h = h;
    this.fit();
  }

  fit() {
    const v = this.viewport.getBoundingClientRect();
    if (!this.h || !v.height) return;
    this.mode = 'fit';
    this.s = v.height / this.h;
    this.tx = (v.width - this.w * this.s) / 2;
    this.ty = 0;
    this.apply();
  }

  // One image pixel to one device pixel, about the middle of what is shown.
  one() {
    const v = this.viewport.getBoundingClientRect();
    this.by((1 / devicePixelRatio) / this.s, v.width / 2, v.height / 2);
  }

  // Zoomed by `factor` about (`cx`, `cy`), px from the viewport's top left.
  by(factor, cx, cy) {
    if (!this.h) return;
    const s = Math.min(Math.max(this.s * factor, 0.02), 64);
    this.tx = cx - (cx - this.tx) * (s / this.s);
    this.ty = cy - (cy - this.ty) * (s / this.s);
    this.s = s;
    this.mode = 'free';
    this.apply();
  }

  pan(dx, dy) {
    this.tx += dx;
    this.ty += dy;
    if (this.mode === 'fit') this.mode = 'free';
    this.apply();
  }

  apply() {
    const c = this.content.style;
    const one = Math.abs(this.s * devicePixelRatio - 1) < 1e-9;
    // At 1:1 on whole pixels, so that each image pixel falls on one screen pixel.
    if (one) { this.tx = Math.round(this.tx); this.ty = Math.round(this.ty); }
    c.left = `${this.tx}px`;
    c.top = `${this.ty}px`;
    c.width = `${this.w * this.s}px`;
    c.height = `${this.h * this.s}px`;
    this.content.classList.toggle('magnified', this.s * devicePixelRatio >= 1);
    const ratio = this.s * devicePixelRatio;
    const text = ratio >= 1 ? `${+ratio.toFixed(2)}:1` : `1:${+(1 / ratio).toFixed(2)}`;
    this.output.textContent = this.mode === 'fit' ? `fit (${text})` : text;
    this.viewport.dataset.zoom = String(ratio);
    this.viewport.dataset.mode = this.mode;
    this.changed();
  }

  // The image pixel [x, y] under the client point, or null off the picture.
  at(clientX, clientY) {
    const r = this.content.getBoundingClientRect();
    const x = Math.floor(((clientX - r.left) / r.width) * this.w);
    const y = Math.floor(((clientY - r.top) / r.height) * this.h);
    return x >= 0 && y >= 0 && x < this.w && y < this.h ? [x, y] : null;
  }

  listen() {
    const v = this.viewport;
    const local = (e) => { const r = v.getBoundingClientRect(); return [e.clientX - r.left, e.clientY - r.top]; };
    v.addEventListener('wheel', (e) => {
      e.preventDefault();
      this.by(2 ** (-e.deltaY / 300), ...local(e));
    }, { passive: false });
    let drag = null;
    v.addEventListener('pointerdown', (e) => {
      if (e.button !== 0) return;
      drag = [e.clientX, e.clientY];
      v.setPointerCapture(e.pointerId);
      v.focus({ preventScroll: true });
    });
    v.addEventListener('pointermove', (e) => {
      if (!drag) return;
      this.pan(e.clientX - drag[0], e.clientY - drag[1]);
      drag = [e.clientX, e.clientY];
    });
    const end = () => { drag = null; };
    v.addEventListener('pointerup', end);
    v.addEventListener('pointercancel', end);
    v.addEventListener('keydown', (e) => {
      if (e.ctrlKey || e.metaKey || e.altKey) return;
      const r = v.getBoundingClientRect();
      const keys = {
        '+': () => this.by(STEP, r.width / 2, r.height / 2),
        '=': () => this.by(STEP, r.width / 2, r.height / 2),
        '-': () => this.by(1 / STEP, r.width / 2, r.height / 2),
        '0': () => this.fit(),
        z: () => this.one(),
        Z: () => this.one(),
        ArrowLeft: () => this.pan(40, 0),
        ArrowRight: () => this.pan(-40, 0),
        ArrowUp: () => this.pan(0, 40),
        ArrowDown: () => this.pan(0, -40),
      };
      const act = keys[e.key];
      if (!act) return;
      e.preventDefault();
      // The page's own keys (the panels' 1–6, walking's arrows) are not these.
      e.stopPropagation();
      act();
    });
  }

  // The zoom's buttons: fit, 1:1, out, in.
  buttons(fit, one, out, zoomIn) {
    const middle = () => { const r = this.viewport.getBoundingClientRect(); return [r.width / 2, r.height / 2]; };
    fit.addEventListener('click', () => this.fit());
    one.addEventListener('click', () => this.one());
    out.addEventListener('click', () => this.by(1 / STEP, ...middle()));
    zoomIn.addEventListener('click', () => this.by(STEP, ...middle()));
  }
}
