// The farm panel: the coordinator's jobs and workers as the live events say they stand.

import { cancelJob, resultUrl } from './api.js';

const jobs = new Map();
const workers = new Map();
let onShow = () => {};
let onError = () => {};

export function init({ show, error }) {
  onShow = show;
  onError = error;
  setInterval(renderWorkers, 1000);
}

export function snapshot(data) {
  jobs.clear();
  workers.clear();
  for (const j of data.jobs) jobs.set(j.id, { ...j, at: Date.now() });
  for (const w of data.workers) workers.set(w.id, { ...w, at: Date.now() });
  renderJobs();
  renderWorkers();
}

export function job(j) { jobs.set(j.id, { ...j, at: Date.now() }); renderJobs(); }
export function jobGone({ id }) { jobs.delete(id); renderJobs(); }
export function worker(w) { workers.set(w.id, { ...w, at: Date.now() }); renderWorkers(); }
export function workerGone({ id }) { workers.delete(id); renderWorkers(); }
export function jobById(id) { return jobs.get(id); }
// Every job the farm holds.
export function allJobs() { return [...jobs.values()]; }
// The finished stills, oldest first (a sequence's frames are shown by sequence.js).
export function doneJobs() { return [...jobs.values()].filter((j) => j.state === 'done' && !j.frames_total); }

function cell(text, cls) {
  const td = document.createElement('td');
  td.textContent = text;
  if (cls) td.className = cls;
  return td;
}

export function duration(s) {
  if (!Number.isFinite(s)) return '–';
  if (s < 60) return `${s.toFixed(1)} s`;
  const m = Math.floor(s / 60);
  return `${m} min ${Math.round(s - 60 * m)} s`;
}

function progressCell(j) {
  const td = document.createElement('td');
  const bar = document.createElement('progress');
  bar.max = Math.max(j.tiles_total, 1);
  bar.value = j.tiles_done;
  bar.setAttribute('aria-label', `${j.name}: tiles done`);
  td.append(` ${progressText(j)}`);
  return td;
}

// `12/60 tiles`, and while it renders `, about 20.5 s left` (from the time per tile so far).
export function progressText(j) {
  let text = `${j.tiles_done}/${j.tiles_total} tiles`;
  if (!j.finished && j.tiles_done > 0 && j.tiles_done < j.tiles_total) {
    const eta = j.elapsed_s * (j.tiles_total - j.tiles_done) / j.tiles_done;
    text += `, about ${duration(eta)} left`;
  }
  return text;
}

// What each result file is, by how its name ends (the first that matches).
const RESULT_KINDS = [
  ['-retinex.exr', 'as seen (Retinex, adapted to its light), linear CIE XYZ'],
  ['-retinex.png', 'as seen (Retinex, adapted to its light), sRGB'],
  ['.exr', 'as rendered, linear CIE XYZ in cd/m²'],
  ['.png', 'as rendered, sRGB at its exposure'],
  ['.json', 'its figures'],
];

// A link to result file `name` of job `id`, saying what it is (a PNG opens, the rest downloads).
export function resultLink(id, name) {
  const a = document.createElement('a');
  a.href = resultUrl(id, name);
  a.textContent = name;
  a.title = `${name}: ${RESULT_KINDS.find(([end]) => name.endsWith(end))?.[1] ?? 'a result file'} (${name.endsWith('.png') ? 'opens' : 'downloads'})`;
  if (!name.endsWith('.png')) a.download = name;
  return a;
}

function button(text, label, onClick) {
  const b = document.createElement('button');
  b.type = 'button';
  b.textContent = text;
  b.setAttribute('aria-label', label);
  b.title = label;
  b.addEventListener('click', onClick);
  return b;
}

function renderJobs() {
  const body = document.querySelector('#jobs tbody');
  const rows = [...jobs.values()].sort((a, b) => a.name.localeCompare(b.name));
  body.replaceChildren(...rows.map((j) => {
    const tr = document.createElement('tr');
    tr.dataset.job = j.id;
    const state = cell(j.state, `state-${j.state}`);
    if (j.error) state.title = j.error;
    const results = document.createElement('td');
    // A sequence's files are its frames', four each: shown and listed by frame in its panel.
    if (j.frames_total) results.append(`${j.frames_ready} of ${j.frames_total} frames`);
    else for (const name of j.results) results.append(resultLink(j.id, name), ' ');
    const actions = document.createElement('td');
    const showable = j.frames_total ? j.frames_ready > 0 : j.state === 'done' && j.results.some((n) => n.endsWith('.png'));
    if (showable) actions.append(button('Show', `Show ${j.name}`, () => onShow(j)));
    if (!j.finished) {
      actions.append(button('Cancel', `Cancel ${j.name}`, () => cancelJob(j.id).then(job, onError)));
    }
    tr.append(cell(j.name), state, progressCell(j), cell(`${j.width} × ${j.height}`, 'number'),
      cell(duration(j.elapsed_s), 'number'), results, actions);
    if (j.error) tr.append(cell(j.error, 'error'));
    return tr;
  }));
  document.getElementById('no-jobs').hidden = jobs.size > 0;
}

function renderWorkers() {
  const body = document.querySelector('#workers tbody');
  const rows = [...workers.values()].sort((a, b) => a.name.localeCompare(b.name));
  body.replaceChildren(...rows.map((w) => {
    const tr = document.createElement('tr');
    tr.dataset.worker = w.id;
    const seen = w.last_seen_s + (Date.now() - w.at) / 1000;
    tr.append(cell(w.name), cell(`${w.leases} of ${w.capacity} tiles`), cell(String(w.tiles_done), 'number'),
      cell(String(w.tiles_failed), 'number'), cell(`${seen.toFixed(0)} s ago`, 'number'), cell(w.build));
    return tr;
  }));
  document.getElementById('no-workers').hidden = workers.size > 0;
}
