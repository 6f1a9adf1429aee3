// The material panel: what the clicked surface is (object, part, material) and what it is made
// of: each state's reflectance spectrum 380–780 nm, plotted, with its colour and L*a*b* under
// D65 as restauro computes them.

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

// Shows the surface `picked` ({object, part, material}) of the scene `view`.
export function show(panel, picked, view) {
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
    '<th scope="col">Colour (D65)</th><th scope="col">L*</th><th scope="col">a*</th><th scope="col">b*</th></tr></thead>';
  const tbody = document.createElement('tbody');
  for (const s of m.states) {
    const tr = document.createElement('tr');
    tr.dataset.state = s.state;
    const swatch = document.createElement('span');
    swatch.className = 'swatch';
    swatch.style.background = css(s.colour_linear_srgb);
    swatch.setAttribute('aria-label', `colour of ${s.spectrum}`);
    const cells = [s.state, s.spectrum, swatch, ...s.lab.map((v) => v.toFixed(1))];
    for (const c of cells) {
      const td = document.createElement('td');
      td.append(c);
      tr.append(td);
    }
    tbody.append(tr);
  }
  states.append(tbody);
  body.append(states, plot(m.states));
}
