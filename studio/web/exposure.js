// How a snapshot is shown as rendered: at an exposure in EV from the automatic one (the
// reference white 2^−EV times the automatic white, drawn by the server exactly as `restauro
// display --exposure absolute:<cd/m²>` draws it), or in false colour by luminance, cd/m², on a
// logarithmic viridis scale whose ends are given.

import * as api from './api.js';
import { viridisScale } from './colour_scale.js';

const $ = (id) => document.getElementById(id);
const luminances = new Map();
let redraw = () => {};

const job = (id) => encodeURIComponent(id);

// The luminances of `j`'s image (fetched once), filling the false-colour range the first time.
export async function prepare(j) {
  if (!luminances.has(j.id)) luminances.set(j.id, await api.call('GET', `/api/jobs/${job(j.id)}/luminance`));
  const l = luminances.get(j.id);
  $('fc-min').value = l.scale_min_cd_m2;
  $('fc-max').value = l.scale_max_cd_m2;
  return l;
}

// The address of `j`'s image as rendered under the controls: null for the farm's own PNG.
export function url(j) {
  const l = luminances.get(j.id);
  if (!l) return null;
  if ($('false-colour').getAttribute('aria-pressed') === 'true') {
    const q = new URLSearchParams({ min_cd_m2: $('fc-min').value, max_cd_m2: $('fc-max').value });
    scale(Number($('fc-min').value), Number($('fc-max').value));
    return `/api/jobs/${job(j.id)}/luminance.png?${q}`;
  }
  $('fc-scale').replaceChildren();
  const ev = Number($('exposure-ev').value);
  if (ev === 0) return null;
  const white = l.auto_white_cd_m2 * 2 ** -ev;
  return `/api/jobs/${job(j.id)}/display.png?exposure=absolute:${white.toPrecision(6)}`;
}

function readout() {
  const ev = Number($('exposure-ev').value);
  $('exposure-shown').textContent = ev === 0 ? 'auto' : `${ev > 0 ? '+' : ''}${ev} EV`;
}

// The false-colour scale: a tick at each decade, labelled in cd/m².
function scale(min, max) {
  const [a, b] = [Math.log10(min), Math.log10(max)];
  const ticks = [];
  for (let d = Math.ceil(a); d <= Math.floor(b); d += 1) {
    const text = 10 ** d >= 1 ? (10 ** d).toLocaleString('en') : (10 ** d).toPrecision(1);
    ticks.push({ at: (d - a) / (b - a), text });
  }
  ticks.push({ at: 1, text: 'cd/m²', y: 50 });
  const label = `false colour: luminance from ${min} to ${max} cd/m², logarithmic`;
  $('fc-scale').replaceChildren(viridisScale('viridis-luminance', label, ticks));
}

export function init(onChange) {
  redraw = onChange;
  $('exposure-ev').addEventListener('input', () => { readout(); redraw(); });
  for (const id of ['fc-min', 'fc-max']) $(id).addEventListener('change', () => redraw());
  $('false-colour').addEventListener('click', () => {
    const on = $('false-colour').getAttribute('aria-pressed') !== 'true';
    $('false-colour').setAttribute('aria-pressed', String(on));
    redraw();
  });
  readout();
}
