// The pixel under the pointer, read by the server from the snapshot's files (GET
// /api/jobs/{id}/pixel): its luminance in cd/m², its CIELAB as rendered and as seen, and with a
// second snapshot the other's and the ΔE00 between them, as the compare map holds it. One
// request at a time: while one is out, only the latest pointer position waits.

import * as api from './api.js';

const lab = (v) => v.map((x) => x.toFixed(2)).join(', ');
const cd = (v) => `${Number(v.toPrecision(4)).toLocaleString('en', { maximumSignificantDigits: 4 })} cd/m²`;

// The readout's words for the server's answer `p`.
export function words(p) {
  const sky = (light) => (light ? ' (sky: a light source)' : '');
  let text = `x ${p.x}, y ${p.y} px · luminance ${cd(p.luminance_cd_m2)}${sky(p.light_source)} · ` +
    `L*a*b* as rendered ${lab(p.lab_rendered)}`;
  if (p.lab_seen) text += ` · as seen ${lab(p.lab_seen)}`;
  const o = p.compared;
  if (o) {
    text = `A: ${text} | B: luminance ${cd(o.luminance_cd_m2)}${sky(o.light_source)} · L*a*b* as rendered ` +
      `${lab(o.lab_rendered)} | ΔE00 of B against A: ${o.delta_e00 === null ? '– (a light source)' : o.delta_e00.toFixed(2)}`;
  }
  return `${text} (CIELAB as rendered relative to a D65 white of ${cd(p.white_cd_m2)})`;
}

// Follows the pointer over `zoom`'s viewport; `which()` gives [job, other job or null].
export function follow(zoom, output, which) {
  let out = false;
  let waiting = null;
  const ask = async (x, y) => {
    const [job, other] = which();
    if (!job) return;
    out = true;
    const q = new URLSearchParams({ x, y });
    if (other) q.set('other', other);
    try {
      const p = await api.call('GET', `/api/jobs/${encodeURIComponent(job)}/pixel?${q}`);
      output.textContent = words(p);
      output.dataset.x = String(p.x);
      output.dataset.y = String(p.y);
    } catch (e) {
      output.textContent = e.message;
    }
    out = false;
    if (waiting) { const w = waiting; waiting = null; ask(...w); }
  };
  zoom.viewport.addEventListener('pointermove', (e) => {
    const at = zoom.at(e.clientX, e.clientY);
    if (!at) return;
    if (out) waiting = at; else ask(...at);
  });
}
