// Two snapshots compared over the whole view: A (before) and B (after) stacked, a slider
// choosing how much of the width shows A; and the CIEDE2000 layer in place of B, the map the
// server computes as `restauro compare` does, with its viridis scale in ΔE00 and its
// statistics. Zoomable as a snapshot is (zoom.js); the readout gives the pixel under the
// pointer in A and in B and the ΔE00 between them there (readout.js).

import * as api from './api.js';
import * as farm from './farm.js';
import * as layer from './layer.js';
import * as readout from './readout.js';
import { viridisScale } from './colour_scale.js';
import { Zoom } from './zoom.js';

const $ = (id) => document.getElementById(id);
let zoom = null;
// The jobs compared, while the comparison shows.
let pair = [null, null];

const png = (job) => job.results.find((n) => n.endsWith('.png') && !n.endsWith('-retinex.png'));

// The finished jobs in both pickers (the choices kept while they are still there).
export function refresh() {
  const done = farm.doneJobs();
  for (const [id, fallback] of [['compare-a', 0], ['compare-b', done.length - 1]]) {
    const picker = $(id);
    const kept = picker.value;
    picker.replaceChildren(...done.map((j) => new Option(`${j.name} (${j.width} × ${j.height} px)`, j.id)));
    if (done.some((j) => j.id === kept)) picker.value = kept;
    else if (done.length) picker.value = done[Math.max(fallback, 0)].id;
  }
}

function slide() {
  const v = Number($('compare-slider').value);
  for (const id of ['compare-img-b', 'compare-map']) $(id).style.clipPath = `inset(0 0 0 ${v}%)`;
  $('compare-line').style.left = `${v}%`;
  $('compare-line').hidden = v === 0 || v === 100;
  $('compare-slider-shown').textContent = `${v} % A`;
}

function scale(top) {
  const ticks = [0, 0.5, 1].map((t) => ({ at: t, text: t === 1 ? `${top} ΔE00` : String(top * t) }));
  $('compare-scale').replaceChildren(viridisScale('viridis-delta-e', `colour scale: ΔE00 from 0 to ${top}`, ticks));
}

export async function show(onError) {
  const [a, b] = [farm.jobById($('compare-a').value), farm.jobById($('compare-b').value)];
  if (!a || !b) return onError(new Error('choose two finished snapshots to compare'));
  const fresh = $('compare-stage').hidden || pair[0] !== a.id || pair[1] !== b.id;
  pair = [a.id, b.id];
  $('compare-stage').hidden = false;
  $('compare-stage-title').textContent = `Before (A): ${a.name} · after (B): ${b.name}`;
  $('compare-img-a').src = api.resultUrl(a.id, png(a));
  $('compare-img-a').alt = `A: ${a.name}, as rendered`;
  $('compare-img-b').src = api.resultUrl(b.id, png(b));
  $('compare-img-b').alt = `B: ${b.name}, as rendered`;
  $('compare-stats').textContent = '';
  $('compare-scale').replaceChildren();
  if (fresh) {
    // At fit, over the model when both were taken from one place (A's, if known here).
    layer.align(a.id);
    zoom.size(a.width, a.height);
    zoom.fit();
    $('compare-readout').textContent = 'Point at the picture to read a pixel in A and B.';
  }
  try {
    const c = await api.compare(a.id, b.id);
    const s = c.delta_e00;
    $('compare-map').src = api.compareMapUrl(a.id, b.id);
    $('compare-map').alt = `CIEDE2000 between ${a.name} and ${b.name}, pixel by pixel`;
    $('compare-stats').textContent = `ΔE00 of B against A: mean ${s.mean.toFixed(2)}, median ${s.median.toFixed(2)}, ` +
      `95th percentile ${s.p95.toFixed(2)}, max ${s.max.toFixed(1)}; ${(100 * s.share_above_threshold).toFixed(1)} % of ` +
      `${s.pixels.toLocaleString('en')} pixels above ${s.threshold} (CIELAB relative to a D65 white of ${c.white_luminance.toPrecision(4)} cd/m²)`;
    $('compare-stats').dataset.mean = String(s.mean);
    scale(c.scale_max);
  } catch (e) {
    onError(e);
  }
  slide();
}

function layerOn(on) {
  for (const id of ['compare-delta', 'compare-delta-here']) $(id).setAttribute('aria-pressed', String(on));
  $('compare-map').hidden = !on;
  $('compare-img-b').hidden = on;
  $('compare-scale').hidden = !on;
}

export function init(onError) {
  zoom = new Zoom($('compare-viewport'), document.querySelector('#compare-viewport .before-after'), { output: $('compare-zoom') });
  zoom.buttons($('compare-fit'), $('compare-one'), $('compare-out'), $('compare-in'));
  readout.follow(zoom, $('compare-readout'), () => pair);
  $('compare-stage').addEventListener('close', () => { pair = [null, null]; });
  $('compare-go').addEventListener('click', () => show(onError));
  $('compare-slider').addEventListener('input', slide);
  for (const id of ['compare-delta', 'compare-delta-here']) {
    $(id).addEventListener('click', () => layerOn($(id).getAttribute('aria-pressed') !== 'true'));
  }
  layerOn(false);
}
