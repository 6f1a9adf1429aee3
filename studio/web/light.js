// The sun panel: the sun placed by the site (latitude, longitude) and a local date and time, as
// the render places it (NREL's solar position algorithm, on the server). The day's path is
// drawn as a chart of elevation over azimuth, with the chosen time marked; the time slider
// moves along it, and "Set the sun" makes it the scene's sun (a new revision).

import * as api from './api.js';

const NS = 'http://www.w3.org/2000/svg';
const $ = (id) => document.getElementById(id);

function svg(name, attributes) {
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attributes)) e.setAttribute(k, v);
  return e;
}

const minutes = (hhmm) => { const [h, m] = hhmm.split(':').map(Number); return h * 60 + m; };
const hhmm = (total) => `${String(Math.floor(total / 60)).padStart(2, '0')}:${String(total % 60).padStart(2, '0')}`;

let path = [];

// The site and time in the form, as the sun edit and the sun-path query want them.
function site() {
  return {
    latitude_deg: $('sun-latitude').value,
    longitude_deg: $('sun-longitude').value,
    date: $('sun-date').value,
    utc_offset: $('sun-offset').value,
  };
}

// The chart: azimuth 0–360° (N E S W) across, elevation −10–90° up; the horizon drawn.
function chart() {
  const [w, h, left, bottom] = [360, 150, 30, 22];
  const x = (az) => left + (az / 360) * (w - left - 6);
  const y = (el) => h - bottom - ((el + 10) / 100) * (h - bottom - 6);
  const root = svg('svg', { viewBox: `0 0 ${w} ${h}`, role: 'img', class: 'sun-path' });
  root.setAttribute('aria-label', 'the sun over the day: elevation in degrees over azimuth');
  root.append(svg('line', { x1: left, y1: y(0), x2: w - 6, y2: y(0), class: 'horizon' }));
  for (const [az, name] of [[0, 'N'], [90, 'E'], [180, 'S'], [270, 'W'], [360, 'N']]) {
    const t = svg('text', { x: x(az), y: h - 6, 'text-anchor': 'middle' });
    t.textContent = name;
    root.append(t);
  }
  for (const el of [0, 30, 60, 90]) {
    const t = svg('text', { x: left - 4, y: y(el) + 4, 'text-anchor': 'end' });
    t.textContent = `${el}°`;
    root.append(t);
  }
  const up = path.filter((p) => p.elevation_deg > -10);
  root.append(svg('polyline', {
    points: up.map((p) => `${x(p.azimuth_deg).toFixed(1)},${y(p.elevation_deg).toFixed(1)}`).join(' '),
    class: 'path',
  }));
  const now = nearest();
  if (now) root.append(svg('circle', { cx: x(now.azimuth_deg), cy: y(Math.max(now.elevation_deg, -10)), r: 5, class: 'sun' }));
  $('sun-chart').replaceChildren(root);
}

function nearest() {
  const t = Number($('sun-time').value);
  return path.reduce((best, p) => (!best || Math.abs(minutes(p.time) - t) < Math.abs(minutes(best.time) - t) ? p : best), null);
}

function readout() {
  $('sun-time-shown').textContent = hhmm(Number($('sun-time').value));
  const p = nearest();
  $('sun-position').textContent = p
    ? `azimuth ${p.azimuth_deg.toFixed(1)}°, elevation ${p.elevation_deg.toFixed(1)}°${p.elevation_deg < 0 ? ' (below the horizon)' : ''}`
    : '';
  chart();
}

// The newest sun-path request: answers may arrive out of order (the date and the offset changed
// one after the other), and only the answer to the form as it is now may be shown.
let asked = 0;

async function refresh(onError) {
  const mine = ++asked;
  try {
    const answer = await api.sunPath(site());
    if (mine !== asked) return;
    path = answer;
    readout();
  } catch (e) {
    if (mine === asked) onError(e);
  }
}

// Fills the form from the scene's sun (`view.sun`), or a default site.
export function show(view, onError) {
  const s = view.sun && view.sun.site;
  if (s) {
    const m = s.datetime.match(/^(\d{4}-\d{2}-\d{2})T(\d{2}:\d{2})(?::\d{2})?(?:\.\d+)?([+-]\d{2}:\d{2}|Z)$/);
    $('sun-latitude').value = s.latitude_deg;
    $('sun-longitude').value = s.longitude_deg;
    if (m) {
      $('sun-date').value = m[1];
      $('sun-time').value = String(Math.round(minutes(m[2]) / 15) * 15);
      $('sun-offset').value = m[3] === 'Z' ? '+00:00' : m[3];
    }
  }
  $('sun-now').textContent = view.sun
    ? `The scene's sun: azimuth ${view.sun.azimuth_deg.toFixed(1)}°, elevation ${view.sun.elevation_deg.toFixed(1)}°, ` +
      (view.sun.elevation_deg > 0
        ? `${Math.round(view.sun.illuminance_lux).toLocaleString('en')} lx normal to it`
        : 'below the horizon: it lights nothing, the sky still does') +
      (s ? ` (${s.datetime})` : ' (given by its direction)')
    : 'The scene has no sun: setting one adds it.';
  refresh(onError);
}

// The sun edit of the form's site and time.
export function edit() {
  const s = site();
  return {
    edit: 'sun',
    latitude_deg: Number(s.latitude_deg),
    longitude_deg: Number(s.longitude_deg),
    datetime: `${s.date}T${hhmm(Number($('sun-time').value))}:00${s.utc_offset}`,
  };
}

export function init(onError) {
  for (const id of ['sun-latitude', 'sun-longitude', 'sun-date', 'sun-offset']) {
    $(id).addEventListener('change', () => refresh(onError));
  }
  $('sun-time').addEventListener('input', readout);
}
