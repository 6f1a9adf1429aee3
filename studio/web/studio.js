// The studio page: signs in, follows the coordinator's live events, shows the farm and results.

import * as api from './api.js';
import * as farm from './farm.js';
import { Viewer } from './viewer.js';
import * as material from './material.js';
import * as light from './light.js';
import * as compare from './compare.js';
import * as notes from './notes.js';
import * as colours from './colours.js';
import * as variants from './variants.js';
import * as painting from './painting.js';
import * as luminaires from './luminaires.js';
import * as grids from './grids.js';
import * as upload from './upload.js';
import * as panels from './panels.js';
import * as help from './help.js';
import * as layer from './layer.js';
import * as strip from './strip.js';
import * as sequence from './sequence.js';

const $ = (id) => document.getElementById(id);
let events = null;
let viewer = null;
let openScene = '';
// The scene whose geometry the viewer holds (a new revision keeps it), the shipped spectra, and
// the surface last clicked (its panel is drawn again after an edit).
let loadedGeometry = '';
let library = null;
let picked = null;
// The snapshot last taken here: shown as soon as it is done.
let awaited = null;

async function takeSnapshot() {
  if (!viewer || !viewer.view) return showError(new Error('open a scene first'));
  const number = (id) => Number($(id).value);
  const request = {
    camera: viewer.pose(),
    render: {
      width: number('snap-width'),
      height: number('snap-height'),
      samples_per_pixel: number('snap-spp'),
      // Adaptive sampling: a fraction of each pixel's luminance; 0 takes every sample.
      noise_target: number('snap-noise') / 100,
      integrator: $('snap-integrator').value,
      variant: $('snap-variant').value || null,
    },
    revision: viewer.view.revision,
  };
  try {
    const job = await api.takeSnapshot(openScene, request);
    awaited = job.id;
    layer.remember(job.id, request.camera);
    farm.job(job);
    painting.follow(job);
    problem('');
  } catch (e) {
    showError(e);
  }
}

// The scenes the coordinator holds, in the picker; `preferred` (a scene just sent) is opened,
// else the one open stays, else the latest is opened.
async function listScenes(preferred) {
  const list = await api.scenes();
  const picker = $('scene-picker');
  const current = picker.value;
  // A first visit: nothing to look at yet, so the page offers the demo's facade or a folder.
  $('welcome').hidden = list.length > 0;
  if (list.length === 0) return;
  picker.replaceChildren(...list.map((s) => {
    const o = document.createElement('option');
    o.value = s.id;
    o.textContent = `${s.name} (${s.jobs} ${s.jobs === 1 ? 'job' : 'jobs'})`;
    return o;
  }));
  const keep = [preferred, current].find((id) => id && list.some((s) => s.id === id));
  picker.value = keep ?? list[list.length - 1].id;
  if (picker.value !== openScene) await open(picker.value);
}

async function open(id, revision) {
  openScene = id;
  $('scene-status').textContent = 'loading the scene…';
  try {
    const view = await api.scene(id, revision);
    if (!viewer) {
      viewer = new Viewer($('view'));
      // For the browser's console (and the tests): the view's camera and controls.
      window.studioViewer = viewer;
      layer.watch(viewer);
      viewer.onPick = (p) => { picked = p; panels.open(2, false); showMaterial(); };
      viewer.onNote = (title) => notes.open(title);
    }
    if (loadedGeometry !== id) {
      $('material').hidden = true;
      picked = null;
      await viewer.open(view, api.sceneGlbUrl(id, view.revision));
      loadedGeometry = id;
    }
    await present(view);
    $('snap-width').value = view.camera.width;
    $('snap-height').value = view.camera.height;
    const moving = view.coarse_triangles ? ` (${view.coarse_triangles.toLocaleString('en')} while moving)` : '';
    $('scene-status').textContent = `${view.triangles.toLocaleString('en')} triangles${moving}, ` +
      `${view.materials.length} materials`;
    $('view').dataset.scene = id;
  } catch (e) {
    $('scene-status').textContent = '';
    showError(e);
  }
}

// Everything drawn from the scene `view` (a revision): colours and sun in the viewer, the
// hypotheses, views and revisions, the sun panel, the material panel of the surface clicked.
async function present(view) {
  viewer.update(view);
  variants.show(view);
  sequence.show(view);
  colours.show(view);
  viewer.colour(variants.chosen(), colours.look);
  const views = $('view-picker');
  views.replaceChildren(new Option("the scene's camera", ''), ...view.views.map((v) => new Option(v.name, v.name)));
  const list = await api.revisions(openScene);
  const picker = $('revision-picker');
  picker.replaceChildren(...list.map((r) => new Option(`${r.number}: ${r.summary}`, String(r.number))));
  picker.value = String(view.revision);
  $('revert').hidden = view.revision === list[list.length - 1].number;
  $('view').dataset.revision = String(view.revision);
  $('download').href = api.downloadUrl(openScene, view.revision);
  light.show(view, showError);
  luminaires.show(view);
  grids.show(view);
  notes.show(view);
  showMaterial();
}

async function showMaterial() {
  if (!picked || !viewer || !viewer.view) return;
  if (!library) library = await api.spectra().catch((e) => { showError(e); return null; });
  const upload = (name, bytes) => api.uploadSpectrum(openScene, name, bytes);
  material.show($('material'), picked, viewer.view, library, applyEdit, upload);
  $('material').querySelector('.body').append(variants.partControls(picked));
}

// Sends one edit; the page then shows the revision it made. True when it was made.
async function applyEdit(change) {
  try {
    const view = await api.edit(openScene, change);
    problem('');
    await present(view);
    const list = await api.revisions(openScene);
    $('scene-status').textContent = `revision ${view.revision}: ${list[list.length - 1].summary}`;
    return true;
  } catch (e) {
    showError(e);
    return false;
  }
}

function saveView() {
  const name = $('view-name').value.trim();
  if (!name) return showError(new Error('give the view a name first'));
  const { position, target, up, vertical_fov_deg } = viewer.pose();
  applyEdit({ edit: 'save-view', view: { name, position, target, up, vertical_fov_deg } });
}

// The demo's facade, asked for on a first visit: opened as a folder sent from the page is.
async function openDemo() {
  $('open-demo').disabled = true;
  $('welcome-status').textContent = 'writing the facade and sending it to the coordinator…';
  try {
    await opened(await api.openDemo());
  } catch (e) {
    showError(e);
  } finally {
    $('open-demo').disabled = false;
    $('welcome-status').textContent = '';
  }
}

// A scene folder taken (sent from the page, or the demo's): its preview job listed, the scene
// opened in the view.
async function opened({ job, scene }) {
  farm.job(job);
  await listScenes(scene);
}

function walking(on) {
  $('walk').setAttribute('aria-pressed', String(on));
  $('walk-hint').hidden = !on;
}

// Walk mode on or off (G): the eye at 1.6 m over the ground under the camera.
function toggleWalk() {
  if (!viewer || !viewer.view) return;
  const on = !viewer.walker.active;
  const walks = viewer.walk(on);
  if (on && !walks) showError(new Error('there is no ground under the camera to stand on: orbit over the model first'));
  walking(walks);
}

function flyTo(name) {
  const v = viewer.view.views.find((x) => x.name === name);
  if (v) viewer.fly(v); else viewer.home();
}

function status(text, live) {
  const el = $('connection');
  el.textContent = text;
  el.className = live ? 'live' : 'down';
}

// Where the person acted last, and when: an error that follows is shown there, in the server's
// words, beside the row of controls (or the form) it came from; one with no such place (a click
// in the view, the live events) shows over the view.
let actedOn = null;
let actedAt = 0;
const ACTION_PATIENCE_MS = 120000;

function noteAction(e) {
  actedOn = e.submitter || e.target;
  actedAt = performance.now();
}

// The message element beside the controls `el` belongs to, made the first time.
function placeFor(el) {
  if (!el || !el.closest || performance.now() - actedAt > ACTION_PATIENCE_MS) return null;
  const host = el.closest('.actions, form, .fields, .choices, .overlay-head, .panel-body, dialog');
  if (!host || !$('studio').contains(host)) return null;
  let place = host.nextElementSibling;
  if (!place || !place.classList.contains('action-problem')) {
    place = document.createElement('p');
    place.className = 'error action-problem';
    place.setAttribute('role', 'alert');
    host.after(place);
  }
  return place;
}

// The problem shown (or, with no text, every problem shown cleared).
function problem(text) {
  $('problem').textContent = text || '';
  $('problem').hidden = !text;
  if (!text) for (const p of document.querySelectorAll('.action-problem')) p.remove();
}

function showError(e) {
  const text = e.message || String(e);
  const place = placeFor(actedOn);
  if (!place) return problem(text);
  $('problem').hidden = true;
  place.textContent = text;
}

async function askForToken(message) {
  if (events) { events.close(); events = null; }
  status('signed out', false);
  $('sign-out').hidden = true;
  $('sign-in-error').textContent = message || '';
  if (!$('sign-in').open) $('sign-in').showModal();
  $('token').focus();
}

async function signIn(token) {
  try {
    await api.signIn(token);
  } catch (e) {
    await askForToken(e.message);
    return;
  }
  $('sign-in').close();
  $('token').value = '';
  await start();
}

async function start() {
  let me;
  try {
    me = await api.whoami();
  } catch (e) {
    if (e.status === 401 || e.status === 403) return askForToken('');
    status('coordinator unreachable', false);
    return showError(e);
  }
  problem(me.problem);
  $('sign-out').hidden = false;
  follow();
  listScenes().catch(showError);
}

// The live events: the browser reconnects by itself and sends Last-Event-ID, so the page is sent
// what it missed; a snapshot replaces everything.
function follow() {
  if (events) events.close();
  events = new EventSource('/api/events');
  const on = (kind, handler) => events.addEventListener(kind, (e) => handler(JSON.parse(e.data)));
  events.onopen = () => status('live', true);
  on('snapshot', (data) => { farm.snapshot(data); compare.refresh(); strip.refresh(); sequence.refresh(); });
  on('job', (j) => {
    const isNew = !farm.jobById(j.id);
    farm.job(j);
    painting.update(j);
    sequence.update(j);
    if (j.state === 'done') { compare.refresh(); strip.refresh(); }
    if (layer.current() && layer.current().id === j.id) layer.show(j);
    if (awaited === j.id && j.state === 'done') { awaited = null; layer.show(j); }
    if (isNew) listScenes().catch(showError);
  });
  on('job-gone', (g) => { farm.jobGone(g); strip.refresh(); sequence.refresh(); });
  on('worker', farm.worker);
  on('worker-gone', farm.workerGone);
  events.onerror = async () => {
    status('reconnecting…', false);
    if (events.readyState === EventSource.CLOSED) {
      // Refused, not dropped: the session ended, or the coordinator is gone.
      try { await api.whoami(); follow(); } catch (e) {
        if (e.status === 401) askForToken('The session ended: sign in again.');
        else setTimeout(follow, 2000);
      }
    }
  };
}

function shortcuts() {
  const d = $('shortcuts');
  if (d.open) d.close(); else d.showModal();
}

document.addEventListener('DOMContentLoaded', () => {
  for (const kind of ['click', 'change', 'submit']) document.addEventListener(kind, noteAction, true);
  panels.init();
  help.init();
  // A sequence's frames are shown in its panel, a still over the view.
  const showJob = (j) => {
    if (!j.frames_total) return layer.show(j);
    panels.open(5, true);
    sequence.choose(j.id);
  };
  farm.init({ show: showJob, error: showError });
  // The snapshot layer (a later event about its job does not open it again once closed).
  layer.init(() => viewer, showError);
  strip.init({ show: (j) => layer.show(j), compare: () => compare.show(showError) });
  $('sign-in-form').addEventListener('submit', (e) => {
    e.preventDefault();
    signIn($('token').value);
  });
  $('sign-in').addEventListener('cancel', (e) => e.preventDefault());
  $('sign-out').addEventListener('click', async () => {
    await api.signOut().catch(showError);
    askForToken('');
  });
  $('show-shortcuts').addEventListener('click', shortcuts);
  $('scene-picker').addEventListener('change', (e) => e.target.value && open(e.target.value));
  $('snapshot-form').addEventListener('submit', (e) => { e.preventDefault(); takeSnapshot(); });
  $('home').addEventListener('click', () => { if (viewer && viewer.view) { viewer.home(); walking(false); } });
  $('revision-picker').addEventListener('change', (e) => open(openScene, Number(e.target.value)));
  $('revert').addEventListener('click', async () => {
    try { await present(await api.revert(openScene, viewer.view.revision)); } catch (e) { showError(e); }
  });
  $('view-picker').addEventListener('change', (e) => { if (viewer) { flyTo(e.target.value); walking(false); } });
  $('save-view').addEventListener('click', () => viewer && viewer.view && saveView());
  $('delete-view').addEventListener('click', () => {
    const name = $('view-picker').value;
    if (!name) return showError(new Error("choose a saved view to delete (the scene's camera stays)"));
    applyEdit({ edit: 'delete-view', name });
  });
  $('set-sun').addEventListener('click', () => viewer && viewer.view && applyEdit(light.edit()));
  light.init(showError);
  compare.init(showError);
  sequence.init({
    error: showError,
    done: () => problem(''),
    scene: () => openScene,
    viewer: () => viewer,
    hypothesis: () => $('snap-variant').value || null,
  });
  upload.init({ error: showError, opened });
  $('open-demo').addEventListener('click', openDemo);
  luminaires.init({
    edit: applyEdit,
    error: showError,
    picked: () => picked,
    scene: () => openScene,
  });
  grids.init({
    // Errors are shown by the grids' own form, where the action was taken.
    edit: async (change) => {
      const view = await api.edit(openScene, change);
      problem('');
      await present(view);
      return view;
    },
    picked: () => picked,
    viewer: () => viewer,
    scene: () => openScene,
  });
  variants.init({
    edit: applyEdit,
    error: showError,
    changed: (v) => { if (viewer && viewer.view) { viewer.colour(v); showMaterial(); } },
  });
  colours.init(() => { if (viewer && viewer.view) { viewer.colour(undefined, colours.look); showMaterial(); } });
  notes.init({
    edit: applyEdit,
    error: showError,
    upload: (name, bytes) => api.uploadImage(openScene, name, bytes),
    url: api.imageUrl,
    fly: (n) => { if (n.pose && viewer) { viewer.fly(n.pose); walking(false); } },
    picked: () => picked,
    pose: () => {
      const { position, target, up, vertical_fov_deg } = viewer.pose();
      return { position, target, up, vertical_fov_deg };
    },
  });
  $('walk').addEventListener('click', () => toggleWalk());
  document.addEventListener('keydown', (e) => {
    if (e.target instanceof HTMLInputElement || e.target instanceof HTMLSelectElement) return;
    if (e.target instanceof HTMLTextAreaElement || e.ctrlKey || e.metaKey || e.altKey) return;
    if (viewer && viewer.walker.active && viewer.walker.key(e, true)) { e.preventDefault(); return; }
    // The arrows and + − move the view when it (or nothing) has the focus and no snapshot lies
    // over it (over a snapshot, they zoom and pan the picture).
    const free = $('result').hidden && $('compare-stage').hidden && $('sequence-stage').hidden;
    const onView = free && (document.activeElement === $('view') || document.activeElement === document.body);
    if (onView && viewer && viewer.nudge(e)) { e.preventDefault(); return; }
    if (e.key === '?') shortcuts();
    if ((e.key === 'h' || e.key === 'H') && viewer && viewer.view) { viewer.home(); walking(false); }
    if (e.key === 'g' || e.key === 'G') toggleWalk();
    if ((e.key === 'v' || e.key === 'V') && viewer && viewer.view) variants.next();
    if (e.key === 'p' || e.key === 'P') panels.showSidebar(!panels.sidebarOpen());
    if (/^[1-6]$/.test(e.key) && panels.key(e.key)) e.preventDefault();
    if (e.key === 'Escape') {
      if (viewer && viewer.walker.active) toggleWalk();
      else if (!document.querySelector('dialog[open]')) panels.closeFront();
    }
  });
  document.addEventListener('keyup', (e) => { if (viewer) viewer.walker.key(e, false); });
  // `restauro studio` prints an address whose fragment carries the token: it is taken from
  // there (a fragment never reaches a server or a log) and removed from the address bar.
  const token = new URLSearchParams(location.hash.slice(1)).get('token');
  if (token) {
    history.replaceState(null, '', location.pathname);
    signIn(token);
  } else {
    start();
  }
});
