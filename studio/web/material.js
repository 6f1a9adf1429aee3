// The material panel: what the clicked surface is (object, part, material) and what it is made
// of: each state's reflectance spectrum 380–780 nm, plotted, with its colour and L*a*b* under
// the light the preview colours under, as restauro computes them; and the controls that change it: another shipped spectrum for
// a state (searched, each candidate plotted beside the current ones), the reflection model and
// its roughness. Each change is sent as an edit; the panel is then drawn again from the scene's
// new revision, as the server keeps it.

import * as colours from './colours.js';

const NS = 'http://www.w3.org/2000/svg';
const FIRST_NM = 380;
const STEP_NM = 5;

// IEC 61966-2-1 encoding of a linear value.
const encode = (v) => (v <= 0.0031308 ? 12.92 * v : 1.055 * v ** (1 / 2.4) - 0.055);
const css = (rgb) => `rgb(${rgb.map((v) => Math.round(255 * encode(v))).join(' ')})`;

function svg(name, attributes) {
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attributes)) e.setAttribute(k, v);
  return e;
}

// ρ(λ) of every state in one plot, with its axes in nm and 0–1.
function plot(states) {
  const [w, h, left, bottom] = [360, 170, 34, 26];
  const root = svg('svg', { viewBox: `0 0 ${w} ${h}`, role: 'img', class: 'spectrum' });
  root.setAttribute('aria-label', `reflectance spectra, ${FIRST_NM} to 780 nm: ${states.map((s) => s.state).join(', ')}`);
  const x = (nm) => left + (nm - FIRST_NM) / 400 * (w - left - 8);
  const y = (r) => h - bottom - r * (h - bottom - 8);
  root.append(svg('line', { x1: left, y1: y(0), x2: w - 8, y2: y(0), class: 'axis' }));
  root.append(svg('line', { x1: left, y1: y(0), x2: left, y2: y(1), class: 'axis' }));
  for (const nm of [400, 500, 600, 700]) {
    const t = svg('text', { x: x(nm), y: h - 8, 'text-anchor': 'middle' });
    t.textContent = nm;
    root.append(t);
  }
  for (const r of [0, 0.5, 1]) {
    const t = svg('text', { x: left - 4, y: y(r) + 4, 'text-anchor': 'end' });
    t.textContent = r;
    root.append(t);
  }
  const unit = svg('text', { x: w - 8, y: h - 8, 'text-anchor': 'end' });
  unit.textContent = 'nm';
  root.append(unit);
  for (const s of states) {
    const points = s.reflectance.map((r, i) => `${x(FIRST_NM + STEP_NM * i).toFixed(1)},${y(r).toFixed(1)}`);
    const line = svg('polyline', { points: points.join(' '), class: `state-${s.state}` });
    line.style.stroke = css(s.colour_linear_srgb);
    root.append(line);
  }
  return root;
}

function row(table, label, value) {
  const tr = document.createElement('tr');
  const th = document.createElement('th');
  th.scope = 'row';
  th.textContent = label;
  const td = document.createElement('td');
  td.append(value);
  tr.append(th, td);
  table.append(tr);
}

// The controls that change material `m`: `library` is /api/spectra, `onEdit` sends an edit,
// `upload(name, bytes)` sends a measured spectrum (CSV) and answers what the server read.
function editor(m, library, onEdit, upload) {
  const form = document.createElement('form');
  form.className = 'material-edit';
  form.setAttribute('aria-label', `Change ${m.name}`);
  const id = (k) => `material-${k}`;
  form.innerHTML = `<h4>Change ${m.name}</h4>
    <label for="${id('state')}">State</label>
    <select id="${id('state')}"><option value="base">base (the material itself)</option>
      <option value="degraded">degraded (as found)</option><option value="cleaned">cleaned</option></select>
    <label for="${id('search')}">Search the shipped spectra</label>
    <input id="${id('search')}" type="search" placeholder="travertine, marble, brick…" autocomplete="off">
    <label for="${id('spectrum')}">Spectrum</label>
    <select id="${id('spectrum')}" size="6"></select>
    <label for="${id('csv')}">Or a measured spectrum: a CSV file of wavelength (nm) and reflectance (0–1)</label>
    <input id="${id('csv')}" type="file" accept=".csv,.txt">
    <p id="${id('candidate')}" class="candidate" aria-live="polite"></p>
    <button type="button" id="${id('assign')}">Assign spectrum</button>
    <label for="${id('model')}">Model</label>
    <select id="${id('model')}"><option value="lambert">Lambert (matte)</option>
      <option value="cook-torrance">Cook–Torrance (glossy)</option></select>
    <label for="${id('roughness')}">Roughness m (Beckmann rms slope, 0–1)</label>
    <input id="${id('roughness')}" type="number" min="0.01" max="1" step="0.01">
    <button type="button" id="${id('apply-model')}">Apply model</button>`;
  const $ = (k) => form.querySelector(`#${id(k)}`);
  $('model').value = m.model;
  $('roughness').value = m.roughness ?? 0.3;
  const fill = () => {
    const words = $('search').value.toLowerCase().split(/\s+/).filter(Boolean);
    const match = (s) => words.every((w) => `${s.name} ${s.material}`.toLowerCase().includes(w));
    $('spectrum').replaceChildren(...library.filter(match).map((s) => new Option(`${s.name} — ${s.material}`, s.name)));
  };
  // The spectrum to assign: one of the list, or the file sent last (until one is chosen).
  let sent = null;
  const candidate = () => sent || library.find((s) => s.name === $('spectrum').value);
  const propose = (c) => {
    $('candidate').textContent = `${c.name}, under D65: L* ${c.lab[0].toFixed(1)}, a* ${c.lab[1].toFixed(1)}, b* ${c.lab[2].toFixed(1)}` +
      (c.notes && c.notes.length ? ` (${c.notes.join('; ')})` : '');
    const plotted = form.parentElement.querySelector('svg.spectrum');
    if (plotted) plotted.replaceWith(plot([...m.states, { ...c, state: 'candidate' }]));
  };
  $('search').addEventListener('input', fill);
  $('spectrum').addEventListener('change', () => {
    sent = null;
    const c = candidate();
    if (c) propose(c);
  });
  $('csv').addEventListener('change', async () => {
    const file = $('csv').files[0];
    if (!file || !upload) return;
    $('candidate').textContent = `reading ${file.name}…`;
    try {
      const info = await upload(file.name, await file.arrayBuffer());
      sent = { ...info, name: info.file_name };
      propose(sent);
    } catch (e) {
      sent = null;
      $('candidate').textContent = e.message;
    }
  });
  $('assign').addEventListener('click', () => {
    const c = candidate();
    if (!c) { $('candidate').textContent = 'choose a spectrum in the list, or send a file, first'; return; }
    const change = { edit: 'material', material: m.name, state: $('state').value };
    if (c.reference) Object.assign(change, { file: c.reference, file_name: c.file_name });
    else change.spectrum = c.name;
    onEdit(change);
  });
  $('apply-model').addEventListener('click', () => {
    const model = $('model').value;
    const change = { edit: 'material', material: m.name, model };
    if (model === 'cook-torrance') change.roughness = Number($('roughness').value);
    onEdit(change);
  });
  fill();
  return form;
}

// Shows the surface `picked` ({object, part, material}) of the scene `view`; with `library`
// and `onEdit` (and `upload`, for a measured spectrum), the controls that change its material.
export function show(panel, picked, view, library, onEdit, upload) {
  const m = view.materials.find((x) => x.name === picked.material);
  panel.hidden = false;
  const body = panel.querySelector('.body');
  body.replaceChildren();
  const facts = document.createElement('table');
  row(facts, 'Object', picked.object);
  row(facts, 'Part', picked.part);
  row(facts, 'Material', picked.material);
  if (m) {
    row(facts, 'Model', m.model === 'cook-torrance' ? `Cook–Torrance, roughness ${m.roughness}` : 'Lambert (matte)');
  }
  body.append(facts);
  if (!m) return;
  const states = document.createElement('table');
  states.className = 'states';
  states.innerHTML = '<thead><tr><th scope="col">State</th><th scope="col">Spectrum</th>' +
    '<th scope="col">Colour</th><th scope="col">L*</th><th scope="col">a*</th><th scope="col">b*</th></tr></thead>';
  const caption = document.createElement('caption');
  caption.textContent = `Under ${colours.name()}: each colour as a camera balanced for daylight (D65) shows it; L*a*b* against that light's white (2° observer)`;
  states.prepend(caption);
  const tbody = document.createElement('tbody');
  for (const s of m.states) {
    const tr = document.createElement('tr');
    tr.dataset.state = s.state;
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    const seen = colours.look(s);
    swatch.style.background = css(seen.colour_linear_srgb);
    swatch.setAttribute('aria-label', `colour of ${s.spectrum} under ${colours.name()}`);
    const cells = [s.state, s.spectrum, swatch, ...seen.lab.map((v) => v.toFixed(1))];
    for (const c of cells) {
      const td = document.createElement('td');
      td.append(c);
      tr.append(td);
    }
    tbody.append(tr);
  }
  states.append(tbody);
  body.append(states, plot(m.states));
  if (library && onEdit) body.append(editor(m, library, onEdit, upload));
}
