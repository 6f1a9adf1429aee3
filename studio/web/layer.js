// A finished snapshot shown as an image layer over the whole view: as rendered (at an
// exposure, or in false colour by luminance) or as seen, zoomable (zoom.js) with the pixel
// under the pointer read out (readout.js).
//
// At "fit" the layer lies over the model: the view's camera is put at the snapshot's pose
// (kept for each snapshot taken in this page, in this browser) and the picture, rendered at
// that vertical field of view, is drawn at the view's height, centred. The layer takes the
// pointer (a drag pans the picture, the wheel zooms it), so the model cannot be orbited under
// it; any other move of the camera (H, a saved view, a note's view, walking) closes the layer.
// A restorer reads a snapshot as a record of what the model looks like from one place: a
// picture left over a model seen from elsewhere would line up with nothing, and a silent
// return to the snapshot's pose would undo the move just asked for. Showing the snapshot
// again (its thumbnail in the strip, or Show in the farm) flies back to its pose.

import * as api from './api.js';
import * as exposure from './exposure.js';
import * as readout from './readout.js';
import { Zoom } from './zoom.js';

const $ = (id) => document.getElementById(id);
const KEPT = 'restauro.studio.snapshot-poses';
let shown = null;
let zoom = null;
let viewer = () => null;
let onError = () => {};
// The pose the view was put at for the layer, while it is there.
let aligned = null;
let aligning = false;

function poses() {
  try { return JSON.parse(localStorage.getItem(KEPT) || '{}'); } catch { return {}; }
}

// The pose of snapshot `id`, taken from this page's view (the preview's coordinates).
export function remember(id, pose) {
  const all = poses();
  all[id] = pose;
  // The latest hundred are kept.
  const ids = Object.keys(all);
  for (const old of ids.slice(0, Math.max(0, ids.length - 100))) delete all[old];
  try { localStorage.setItem(KEPT, JSON.stringify(all)); } catch { /* storage refused */ }
}

export const poseOf = (id) => poses()[id] || null;

// The view's camera at snapshot `id`'s pose; false when its pose is not known here.
export function align(id) {
  const v = viewer();
  const pose = poseOf(id);
  if (!v || !v.view || !pose) { aligned = null; return false; }
  aligning = true;
  if (v.walker.active) v.walk(false);
  v.fly(pose);
  aligning = false;
  aligned = pose;
  return true;
}

// The job shown, if any.
export const current = () => shown;

export function show(job, seen) {
  const fresh = shown === null || shown.id !== job.id || $('result').hidden;
  if (shown === null || shown.id !== job.id) {
    exposure.prepare(job).then(() => shown && shown.id === job.id && show(shown)).catch((e) => onError(e));
  }
  shown = job;
  const name = job.results.find((n) => n.endsWith('.png') && !n.endsWith('-retinex.png'));
  const retinex = job.results.find((n) => n.endsWith('-retinex.png'));
  const useSeen = seen ?? ($('as-seen').getAttribute('aria-pressed') === 'true');
  const file = useSeen && retinex ? retinex : name;
  $('as-seen').disabled = !retinex;
  $('as-rendered').setAttribute('aria-pressed', String(file === name));
  $('as-seen').setAttribute('aria-pressed', String(file === retinex));
  $('result').hidden = false;
  $('result').dataset.job = job.id;
  $('result-title').textContent = `Snapshot: ${job.name}`;
  const img = $('result-image');
  const adjusted = file === name ? exposure.url(job) : null;
  img.src = adjusted ?? api.resultUrl(job.id, file);
  img.alt = `${job.name}, ${file === retinex ? 'as seen, adapted to its light' : 'as rendered'}`;
  if (fresh) {
    const lined = align(job.id);
    $('result').dataset.aligned = String(lined);
    zoom.size(job.width, job.height);
    zoom.fit();
    $('pixel-readout').textContent = 'Point at the picture to read a pixel.';
  }
  const how = adjusted ? (adjusted.includes('luminance.png') ? 'false colour by luminance' : `at ${$('exposure-shown').textContent}`) : file;
  const where = $('result').dataset.aligned === 'true'
    ? 'the view is at its camera: at fit it lies over the model'
    : 'taken outside this page: its camera is not known here, so it is not aligned with the model';
  $('result-caption').textContent = `${how} — ${job.width} × ${job.height} px; ${where}`;
  const downloads = $('result-downloads');
  downloads.replaceChildren();
  for (const n of job.results) {
    const a = document.createElement('a');
    a.href = api.resultUrl(job.id, n);
    a.download = n;
    a.textContent = n;
    downloads.append(a, ' ');
  }
}

// The layer closed (× or Esc): the model again.
function closed() {
  shown = null;
  aligned = null;
}

export function close() {
  if ($('result').hidden) return;
  $('result').hidden = true;
  $('result').dispatchEvent(new Event('close'));
}

// `getViewer()` gives the view (once a scene is open; its camera's moves are watched with
// `watch`), `error` shows a failure.
export function init(getViewer, error) {
  viewer = getViewer;
  onError = error;
  zoom = new Zoom($('result-viewport'), $('result-image'), { output: $('result-zoom') });
  zoom.buttons($('result-fit'), $('result-one'), $('result-out'), $('result-in'));
  readout.follow(zoom, $('pixel-readout'), () => [shown && shown.id, null]);
  $('result').addEventListener('close', closed);
  $('as-rendered').addEventListener('click', () => shown && show(shown, false));
  $('as-seen').addEventListener('click', () => shown && show(shown, true));
  exposure.init(() => shown && show(shown));
}

// Follows the camera of `v`: a move away from the snapshot's pose closes the layer.
export function watch(v) {
  v.controls.addEventListener('change', () => {
    if (aligning || !aligned || $('result').hidden) return;
    const now = v.pose();
    const far = (a, b) => a.some((x, i) => Math.abs(x - b[i]) > 1e-6);
    if (far(now.position, aligned.position) || far(now.target, aligned.target)) close();
  });
}
