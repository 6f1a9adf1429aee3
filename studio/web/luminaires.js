// The sky and the luminaires: the sky's model, diffuse horizontal illuminance and spectrum; each
// luminaire listed (where it stands and what it aims at, in metres in the scene's frame; its peak
// intensity in cd, its flux in lm and beam angle from its photometric file), and a form that
// places one at the point clicked (raised a little), aims it at another, gives its intensity (or
// its flux) or
// an IES / EULUMDAT file (read by the server, which says what is in it) and a spectrum by name.
// Every change is an edit of the scene's `[[lights]]`, checked as a scene file is.

import * as api from './api.js';

const $ = (id) => document.getElementById(id);
// CIE illuminants a luminaire may take by name; the edit adds the one chosen to [spectra].
const CIE = [
  ['cie:A', 'CIE A (incandescent, 2856 K)'],
  ['cie:blackbody:3000', 'black body 3000 K (warm white)'],
  ['cie:blackbody:4000', 'black body 4000 K (neutral white)'],
  ['cie:F11', 'CIE F11 (tri-band fluorescent)'],
  ['cie:D65', 'CIE D65 (daylight)'],
];
let ctx = null;
let view = null;
let editing = null;
let file = null;
// The direction an area light faces (the scene's frame): out of the surface last placed on.
let facing = null;

// The preview's frame (Y up, offset removed) to the scene's (Z up, metres): the inverse of the
// server's `to_glb`.
export function toWorld(p, offset) {
  return [p[0] + offset[0], -p[2] + offset[1], p[1] + offset[2]];
}

const metres = (p) => (p ? `${p.map((v) => v.toFixed(2)).join(', ')}` : '–');
const number = (v, digits = 0) => (v === null || v === undefined ? '–' : v.toLocaleString('en', { maximumFractionDigits: digits }));

// `context`: { edit(change) → Promise<bool>, error(e), picked() → {point} | null, scene() → id }.
export function init(context) {
  ctx = context;
  $('set-sky').addEventListener('click', setSky);
  $('remove-sky').addEventListener('click', () => {
    const sky = view && view.lights.find((l) => l.light.kind === 'sky');
    if (!sky) return ctx.error(new Error('the scene has no sky'));
    ctx.edit({ edit: 'delete-light', index: sky.index });
  });
  $('lum-place').addEventListener('click', () => fromPick(['lum-x', 'lum-y', 'lum-z'], Number($('lum-lift').value) || 0));
  $('lum-aim').addEventListener('click', () => fromPick(['lum-ax', 'lum-ay', 'lum-az'], 0));
  $('lum-file').addEventListener('change', upload);
  $('lum-file-clear').addEventListener('click', () => setFile(null));
  $('lum-new').addEventListener('click', () => startNew());
  $('luminaire-form').addEventListener('submit', (e) => { e.preventDefault(); save(); });
}

function fromPick(ids, lift) {
  const p = ctx.picked();
  if (!p || !view) return ctx.error(new Error('click a surface in the view first'));
  const w = toWorld(p.point, view.offset_m);
  if (ids[0] === 'lum-x' && p.normal) facing = toWorld(p.normal, [0, 0, 0]);
  // An area light is raised off the surface along its normal (it faces out of it); a lamp up.
  const up = $('lum-kind').value === 'area' && ids[0] === 'lum-x' && facing ? facing : [0, 0, 1];
  up.forEach((d, k) => { w[k] += lift * d; });
  ids.forEach((id, k) => { $(id).value = w[k].toFixed(3); });
}

function setFile(info) {
  file = info;
  $('lum-file-info').textContent = info
    ? `${info.file_name}: ${number(info.flux_lm)} lm, peak ${number(info.peak_cd)} cd, beam ${number(info.beam_angle_deg, 1)}°` +
      (info.description ? ` — ${info.description}` : '')
    : '';
  $('lum-file-clear').hidden = !info;
  if (!info) $('lum-file').value = '';
}

async function upload() {
  const chosen = $('lum-file').files[0];
  if (!chosen) return;
  $('lum-file-info').textContent = `reading ${chosen.name}…`;
  try {
    setFile(await api.uploadPhotometry(ctx.scene(), chosen.name, await chosen.arrayBuffer()));
  } catch (e) {
    setFile(null);
    ctx.error(e);
  }
}

function options(select, names, extra) {
  const was = select.value;
  select.replaceChildren(...names.map((n) => new Option(n, n)), ...extra.map(([v, t]) => new Option(t, v)));
  if ([...select.options].some((o) => o.value === was)) select.value = was;
}

// The sky and luminaires of the revision `v`.
export function show(v) {
  view = v;
  options($('sky-spectrum'), v.light_spectra, CIE);
  options($('lum-spectrum'), v.light_spectra, CIE);
  const sky = v.lights.find((l) => l.light.kind === 'sky');
  if (sky) {
    $('sky-model').value = sky.model === 'uniform sky' ? 'uniform' : 'cie-overcast';
    $('sky-lux').value = Math.round(sky.illuminance_lux);
    $('sky-spectrum').value = sky.light.spectrum;
  }
  $('sky-now').textContent = sky
    ? `The scene's sky: ${sky.model}, ${number(sky.illuminance_lux)} lx on the horizontal, spectrum ${sky.light.spectrum}.`
    : 'The scene has no sky: setting one adds it.';
  const rows = v.lights.filter((l) => ['point', 'spot', 'area'].includes(l.light.kind));
  $('no-luminaires').hidden = rows.length > 0;
  $('luminaires').querySelector('tbody').replaceChildren(...rows.map(row));
  if (editing !== null && !rows.some((l) => l.index === editing)) startNew();
}

function row(l) {
  const tr = document.createElement('tr');
  tr.dataset.index = String(l.index);
  const file = l.light.ies ? (l.light.ies.startsWith('blake3:') ? `${l.light.ies.slice(7, 19)}…` : l.light.ies) : 'none';
  const x = l.light;
  const area = x.kind === 'area' ? { centre: x.corner.map((c, k) => c + (x.u[k] + x.v[k]) / 2), w: Math.hypot(...x.u), h: Math.hypot(...x.v) } : null;
  const kind = area ? `area ${area.w.toFixed(2)} × ${area.h.toFixed(2)} m` : x.kind;
  const cells = [l.index, kind, metres(area ? area.centre : x.position), metres(x.aim), number(l.intensity_cd),
    number(l.flux_lm), number(l.beam_angle_deg, 1), l.light.spectrum, file];
  for (const c of cells) {
    const td = document.createElement('td');
    td.textContent = String(c);
    tr.append(td);
  }
  const td = document.createElement('td');
  const change = document.createElement('button');
  change.type = 'button';
  change.textContent = 'Change';
  change.setAttribute('aria-label', `Change luminaire ${l.index}`);
  change.addEventListener('click', () => startEditing(l));
  const remove = document.createElement('button');
  remove.type = 'button';
  remove.textContent = 'Delete';
  remove.setAttribute('aria-label', `Delete luminaire ${l.index}`);
  remove.addEventListener('click', () => ctx.edit({ edit: 'delete-light', index: l.index }));
  td.append(change, ' ', remove);
  tr.append(td);
  return tr;
}

function fill(ids, p) {
  ids.forEach((id, k) => { $(id).value = p ? String(p[k]) : ''; });
}

function startEditing(l) {
  editing = l.index;
  const x = l.light;
  $('lum-kind').value = x.kind;
  fill(['lum-x', 'lum-y', 'lum-z'], x.position);
  if (x.kind === 'area') {
    fill(['lum-x', 'lum-y', 'lum-z'], x.corner.map((c, k) => c + (x.u[k] + x.v[k]) / 2));
    $('lum-width').value = Math.hypot(...x.u);
    $('lum-height').value = Math.hypot(...x.v);
    $('lum-luminance').value = x.luminance_cd_m2 ?? '';
    facing = unit(cross(x.u, x.v));
  }
  fill(['lum-ax', 'lum-ay', 'lum-az'], x.aim);
  $('lum-cd').value = x.intensity_cd ?? '';
  $('lum-lm').value = x.flux_lm ?? '';
  if (x.kind === 'spot') { $('lum-cone').value = x.cone_deg; $('lum-falloff').value = x.falloff_deg; }
  $('lum-spectrum').value = x.spectrum;
  setFile(x.ies ? { reference: x.ies, file_name: 'the file kept', flux_lm: l.flux_lm, peak_cd: l.intensity_cd, beam_angle_deg: l.beam_angle_deg, description: '' } : null);
  $('luminaire-form-title').textContent = `Luminaire ${l.index}`;
  $('lum-save').textContent = `Save luminaire ${l.index}`;
  $('lum-new').hidden = false;
}

function startNew() {
  editing = null;
  setFile(null);
  $('luminaire-form-title').textContent = 'A new luminaire';
  $('lum-save').textContent = 'Add the luminaire';
  $('lum-new').hidden = true;
}

const value = (id) => ($(id).value === '' ? null : Number($(id).value));

const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const unit = (a) => { const n = Math.hypot(...a); return a.map((x) => x / n); };

// An area light centred at the form's position, facing out of the surface it was placed on
// (or towards the point it aims at), its width level (along x on a floor or a ceiling): a
// `[[lights]]` entry whose u × v is the direction it emits to.
function areaLight() {
  const centre = ['lum-x', 'lum-y', 'lum-z'].map(value);
  const aim = ['lum-ax', 'lum-ay', 'lum-az'].map(value);
  const n = aim.every((v) => v !== null) ? unit(aim.map((a, k) => a - centre[k])) : facing;
  if (!n) throw new Error('place the area light at a point clicked (it faces out of that surface), or give the point it aims at');
  const e1 = Math.abs(n[2]) > 0.7 ? unit([1 - n[0] * n[0], -n[0] * n[1], -n[0] * n[2]]) : unit(cross([0, 0, 1], n));
  const e2 = cross(n, e1);
  // A size not given is 0, an edge the server refuses by its name (u or v).
  const [w, h] = [value('lum-width') ?? 0, value('lum-height') ?? 0];
  const l = {
    kind: 'area',
    corner: centre.map((c, k) => c - (w / 2) * e1[k] - (h / 2) * e2[k]),
    u: e1.map((x) => x * w),
    v: e2.map((x) => x * h),
    spectrum: $('lum-spectrum').value,
  };
  const cd = value('lum-luminance');
  if (cd !== null) l.luminance_cd_m2 = cd;
  const lm = value('lum-lm');
  if (lm !== null) l.flux_lm = lm;
  return l;
}

// The luminaire in the form, as a `[[lights]]` entry.
function light() {
  const kind = $('lum-kind').value;
  if (kind === 'area') return areaLight();
  const aim = ['lum-ax', 'lum-ay', 'lum-az'].map(value);
  const l = {
    kind,
    position: ['lum-x', 'lum-y', 'lum-z'].map(value),
    spectrum: $('lum-spectrum').value,
  };
  if (aim.every((v) => v !== null)) l.aim = aim;
  const cd = value('lum-cd');
  if (cd !== null) l.intensity_cd = cd;
  const lm = value('lum-lm');
  if (lm !== null) l.flux_lm = lm;
  if (file) l.ies = file.reference;
  if (kind === 'spot') { l.cone_deg = value('lum-cone'); l.falloff_deg = value('lum-falloff') ?? 0; }
  return l;
}

async function save() {
  let change;
  try { change = { edit: 'save-light', light: light() }; } catch (e) { return ctx.error(e); }
  if (editing !== null) change.index = editing;
  if (await ctx.edit(change) && editing === null) setFile(null);
}

function setSky() {
  const sky = view && view.lights.find((l) => l.light.kind === 'sky');
  const change = {
    edit: 'save-light',
    light: { kind: 'sky', model: $('sky-model').value, illuminance_lux: value('sky-lux'), spectrum: $('sky-spectrum').value },
  };
  if (sky) change.index = sky.index;
  ctx.edit(change);
}
