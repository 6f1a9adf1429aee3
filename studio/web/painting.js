// The snapshot taken here, painted into the real-time view tile by tile as the farm renders it
// (the server draws the tiles it holds, exposed over the pixels so far; the rest is transparent,
// so the preview shows through), with its progress and the time left.

import * as api from './api.js';
import { progressText } from './farm.js';

const $ = (id) => document.getElementById(id);
const ENDED = ['done', 'failed', 'cancelled'];
// The job painted, the tiles its picture shows (or is loading), and the tiles done since.
let painted = null;
let shown = -1;
let wanted = -1;

// Starts painting job `job` (just submitted).
export function follow(job) {
  painted = job.id;
  shown = -1;
  wanted = -1;
  update(job);
}

// A job's new status: the painted one's picture is fetched again when it has more tiles.
export function update(job) {
  if (job.id !== painted) return;
  const img = $('painting');
  const caption = $('painting-progress');
  caption.hidden = false;
  caption.textContent = `Snapshot ${job.name}: ${job.state}, ${progressText(job)}`;
  if (ENDED.includes(job.state)) {
    painted = null;
    img.hidden = true;
    if (job.state === 'done') caption.hidden = true;
    return;
  }
  wanted = job.tiles_done;
  if (img.dataset.loading !== 'true') load();
}

function load() {
  if (painted === null || wanted === shown) return;
  const img = $('painting');
  img.dataset.loading = 'true';
  shown = wanted;
  img.onload = () => { img.dataset.loading = 'false'; img.hidden = painted === null; img.dataset.tiles = String(shown); load(); };
  img.onerror = () => { img.dataset.loading = 'false'; };
  img.src = `/api/jobs/${encodeURIComponent(painted)}/painting.png?tiles=${shown}`;
}

// Hides the picture and its caption (a result is shown in its place).
export function clear() {
  painted = null;
  $('painting').hidden = true;
  $('painting-progress').hidden = true;
}
