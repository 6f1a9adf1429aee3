// A sequence: the sun through a day, or a walk through saved views, of the revision shown, from
// this view, rendered on the farm as one job per hypothesis (the server expands the frames as
// `restauro sequence` does and refuses what it refuses). Its frames come onto a timeline as
// each is ready (the job's `frames_ready`, then `/api/jobs/{id}/frames` for their labels and
// files); the range input scrubs through them, and a second hypothesis's job of the same frames
// shows on the right of a before/after slider at the same frame.

import * as api from './api.js';
import * as farm from './farm.js';

const $ = (id) => document.getElementById(id);
let ctx = null;
// Each shown job's frames as last fetched, and the `frames_ready` each fetch was for.
const frames = new Map();
const asked = new Map();
// The views the walk's field was last filled with (not typed).
let filled = '';

const isSequence = (j) => j.frames_total > 0;
const seen = (files) => files.find((n) => n.endsWith('-retinex.png'));
const rendered = (files) => files.find((n) => n.endsWith('.png') && !n.endsWith('-retinex.png'));

// The picture of a ready frame to show: as seen when the farm wrote one (a coordinator run with
// --no-retinex writes none), else as rendered.
function picture(files) {
  return ($('seq-look').value === 'seen' && seen(files)) || rendered(files);
}

function kind() {
  return $('seq-kind-walk').checked ? 'walk' : 'day';
}

function kindShown() {
  $('seq-day').hidden = kind() !== 'day';
  $('seq-walk').hidden = kind() !== 'walk';
}

// The page's words for the server: clock times, a step, view names, fps and m/s as typed.
function request() {
  const number = (id) => Number($(id).value);
  const sequence = kind() === 'day'
    ? { kind: 'day', from: $('seq-from').value, to: $('seq-to').value, every: $('seq-every').value.trim(), date: $('seq-date').value || null }
    : {
      kind: 'walk',
      views: $('seq-views').value.split(',').map((s) => s.trim()).filter(Boolean),
      fps: number('seq-fps'),
      speed_m_s: number('seq-speed'),
    };
  const hypotheses = [ctx.hypothesis()];
  if ($('seq-compare-with').value !== '') hypotheses.push(JSON.parse($('seq-compare-with').value));
  return {
    sequence,
    camera: ctx.viewer().pose(),
    render: { width: number('seq-width'), height: number('seq-height'), samples_per_pixel: number('seq-spp') },
    hypotheses,
    revision: ctx.viewer().view.revision,
  };
}

async function start() {
  const viewer = ctx.viewer();
  if (!viewer || !viewer.view) return ctx.error(new Error('open a scene first'));
  try {
    const started = await api.startSequence(ctx.scene(), request());
    for (const j of started.jobs) farm.job(j);
    refresh();
    $('seq-a').value = started.jobs[0].id;
    refresh();
    $('seq-b').value = started.jobs[1] ? started.jobs[1].id : '';
    $('seq-scrub').value = '0';
    ctx.done();
    follow();
  } catch (e) {
    ctx.error(e);
  }
}

// The scene's hypotheses to compare with, and its saved views for a walk.
export function show(view) {
  const picker = $('seq-compare-with');
  const kept = picker.value;
  picker.replaceChildren(new Option('nothing (one job)', ''), new Option('as the scene is', 'null'),
    ...view.variants.map((v) => new Option(v.name, JSON.stringify(v.name))));
  if ([...picker.options].some((o) => o.value === kept)) picker.value = kept;
  const names = view.views.map((v) => v.name).join(', ');
  $('seq-views').placeholder = names || 'save two views first (panel 1)';
  // Every saved view, in order, until the person writes a walk of their own.
  if (!$('seq-views').value || $('seq-views').value === filled) $('seq-views').value = names;
  filled = names;
}

// The farm's sequences in the pickers (the choices kept while they are there): A any, B one of
// as many frames and the same size, for the slider.
export function refresh() {
  const all = farm.allJobs().filter(isSequence);
  const label = (j) => `${j.name} (${j.frames_total} frames, ${j.width} × ${j.height} px)`;
  const a = $('seq-a');
  const keptA = a.value;
  a.replaceChildren(...all.map((j) => new Option(label(j), j.id)));
  if (all.some((j) => j.id === keptA)) a.value = keptA;
  const first = farm.jobById(a.value);
  const b = $('seq-b');
  const keptB = b.value;
  const like = first ? all.filter((j) => j.id !== first.id && j.frames_total === first.frames_total
    && j.width === first.width && j.height === first.height) : [];
  b.replaceChildren(new Option('nothing', ''), ...like.map((j) => new Option(label(j), j.id)));
  if (like.some((j) => j.id === keptB)) b.value = keptB;
  follow();
}

// Sequence `id` (a job of the farm's) shown as A, its panel open and in sight.
export function choose(id) {
  refresh();
  $('seq-a').value = id;
  refresh();
  $('sequence').scrollIntoView({ block: 'nearest' });
}

// A job's status from the live events: its frames fetched again when more are ready.
export function update(j) {
  if (isSequence(j) && [...$('seq-a').options].every((o) => o.value !== j.id)) refresh();
  if (j.id === $('seq-a').value || j.id === $('seq-b').value) follow();
}

// Fetches the frames of A and B that became ready since the last fetch (those from the first
// not ready then: the ones before cannot change), then draws.
function follow() {
  for (const id of [$('seq-a').value, $('seq-b').value]) {
    const j = id && farm.jobById(id);
    if (!j || asked.get(id) === j.frames_ready) continue;
    asked.set(id, j.frames_ready);
    const was = frames.get(id);
    const from = was ? was.frames_ready : 0;
    api.sequenceFrames(id, from).then((f) => {
      const now = frames.get(id);
      if (now && now.frames_ready > f.frames_ready) return;
      const before = now ? now.frames.slice(0, from) : [];
      frames.set(id, { ...f, frames: before.concat(f.frames) });
      draw();
    }, (e) => { asked.delete(id); ctx.error(e); });
  }
  draw();
}

function progressOf(j, index) {
  const p = j && j.frames.find((f) => f.index === index);
  return p ? `${p.tiles_done}/${p.tiles_total} tiles` : 'waiting';
}

function item(a, f, job) {
  const li = document.createElement('li');
  li.dataset.frame = String(f.index);
  const ready = f.files.length > 0;
  li.dataset.ready = String(ready);
  const b = document.createElement('button');
  b.type = 'button';
  b.setAttribute('aria-label', `Frame ${f.index + 1}: ${f.label}${ready ? '' : ', not ready yet'}`);
  b.title = `Show frame ${f.index + 1} (${f.label})`;
  if (ready) {
    const img = document.createElement('img');
    img.src = api.resultUrl(a.job, picture(f.files));
    img.alt = '';
    img.loading = 'lazy';
    b.append(img);
  }
  const text = document.createElement('span');
  text.textContent = ready ? f.label : `${f.label} · ${progressOf(job, f.index)}`;
  b.append(text);
  b.addEventListener('click', () => { $('seq-scrub').value = String(f.index); showFrame(); });
  li.append(b);
  return li;
}

// The timeline as A's frames stand (an item is made again only when its frame changes).
function draw() {
  const a = frames.get($('seq-a').value);
  const b = $('seq-b').value ? frames.get($('seq-b').value) : null;
  $('seq-player').hidden = !a;
  if (!a) {
    if (!$('sequence-stage').hidden) overView(false);
    $('seq-status').textContent = farm.allJobs().some(isSequence) ? '' : 'No sequence yet.';
    return;
  }
  const jobA = farm.jobById(a.job);
  const jobB = b && farm.jobById(b.job);
  const state = (j, f) => `${f.name}: ${f.frames_ready} of ${f.frames.length} frames ready` +
    (j && j.state !== 'running' && j.state !== 'done' ? ` (${j.state}${j.error ? `: ${j.error}` : ''})` : '');
  $('seq-status').textContent = [state(jobA, a), b && state(jobB, b)].filter(Boolean).join('; ');
  const list = $('seq-timeline');
  const key = (f) => `${a.job}/${f.index}/${f.files.length}/${$('seq-look').value}/${f.files.length ? '' : progressOf(jobA, f.index)}`;
  const kept = new Map([...list.children].map((li) => [li.dataset.key, li]));
  list.replaceChildren(...a.frames.map((f) => {
    const li = kept.get(key(f)) || item(a, f, jobA);
    li.dataset.key = key(f);
    return li;
  }));
  const scrub = $('seq-scrub');
  scrub.max = String(Math.max(a.frames.length - 1, 0));
  $('seq-view').style.aspectRatio = jobA ? `${jobA.width} / ${jobA.height}` : '16 / 9';
  fitOver();
  showFrame();
}

// Frame n (the scrub's) of A, and of B on the slider's right.
function showFrame() {
  const a = frames.get($('seq-a').value);
  if (!a) return;
  const b = $('seq-b').value ? frames.get($('seq-b').value) : null;
  const n = Math.min(Number($('seq-scrub').value), a.frames.length - 1);
  const f = a.frames[n];
  $('seq-label').textContent = `${f.label} (frame ${n + 1} of ${a.frames.length})`;
  $('seq-label').dataset.frame = String(n);
  for (const li of $('seq-timeline').children) li.setAttribute('aria-current', String(li.dataset.frame === String(n)));
  const missing = [];
  const place = (img, side, sequence) => {
    const g = sequence && sequence.frames[n];
    const ready = g && g.files.length > 0;
    img.hidden = !ready;
    if (!ready) {
      if (sequence) missing.push(`${side} (${sequence.name}) has not rendered frame ${n + 1} yet`);
      img.removeAttribute('src');
      delete img.dataset.job;
      return;
    }
    const file = picture(g.files);
    const src = api.resultUrl(sequence.job, file);
    if (img.getAttribute('src') !== src) img.src = src;
    img.dataset.job = sequence.job;
    img.dataset.frame = String(n);
    img.alt = `${side}: ${sequence.name}, frame ${n + 1} (${g.label}), ${file === seen(g.files) ? 'as seen' : 'as rendered'}`;
  };
  place($('seq-img-a'), 'A', a);
  place($('seq-img-b'), 'B', b);
  $('seq-compare').hidden = !b;
  // The shown frame's files of each, to download.
  const links = [a, b].filter(Boolean).flatMap((q) => (q.frames[n] ? q.frames[n].files.map((name) => farm.resultLink(q.job, name)) : []));
  $('seq-downloads').replaceChildren(...links.flatMap((l) => [l, ' ']));
  $('seq-missing').hidden = missing.length === 0;
  $('seq-missing').textContent = missing.join('; ');
  slide();
}

function slide() {
  const v = Number($('seq-slider').value);
  const compared = !$('seq-compare').hidden;
  $('seq-img-b').style.clipPath = `inset(0 0 0 ${v}%)`;
  $('seq-line').style.left = `${v}%`;
  $('seq-line').hidden = !compared || v === 0 || v === 100;
  $('seq-slider-shown').textContent = `${v} % A`;
}

// The frame over the whole view (as large as it fits, its aspect kept), or back in the panel.
function overView(on) {
  $('seq-over').setAttribute('aria-pressed', String(on));
  $('sequence-stage').hidden = !on;
  if (on) $('sequence-stage').append($('seq-view'));
  else $('seq-missing').before($('seq-view'));
  fitOver();
}

function fitOver() {
  const view = $('seq-view');
  const j = farm.jobById($('seq-a').value);
  if ($('sequence-stage').hidden || !j) {
    view.style.width = '';
    view.style.height = '';
    return;
  }
  const r = $('sequence-stage').getBoundingClientRect();
  const s = Math.min(r.width / j.width, r.height / j.height);
  view.style.width = `${Math.floor(j.width * s)}px`;
  view.style.height = `${Math.floor(j.height * s)}px`;
}

// `context`: { error(e), done() (clears a refusal shown), scene(), viewer(), hypothesis() }.
export function init(context) {
  ctx = context;
  for (const id of ['seq-kind-day', 'seq-kind-walk']) $(id).addEventListener('change', kindShown);
  kindShown();
  $('sequence-form').addEventListener('submit', (e) => { e.preventDefault(); start(); });
  $('seq-a').addEventListener('change', refresh);
  $('seq-b').addEventListener('change', follow);
  $('seq-look').addEventListener('change', draw);
  $('seq-scrub').addEventListener('input', showFrame);
  $('seq-slider').addEventListener('input', slide);
  $('seq-over').addEventListener('click', () => overView($('seq-over').getAttribute('aria-pressed') !== 'true'));
  // Closed by its × or Esc (panels.js): the frame goes back to the panel.
  $('sequence-stage').addEventListener('close', () => overView(false));
  window.addEventListener('resize', fitOver);
  draw();
}
