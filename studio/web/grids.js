// The calculation grids: placed on the model by clicking (a rectangle on the plane of the first
// corner clicked, its points at a spacing; or the points of the flat face clicked, at that
// spacing), lifted off the surface along its normal; listed, renamed, deleted — each change an
// edit of the scene's `[[grids]]`, checked as a scene file is. "Compute the grids" runs them on
// the farm; the server reads the result as `restauro illuminance` does, and the page shows its
// figures (min, mean, max in lx, U0 = Emin/Emean, written as the command line writes them) and
// draws each grid's false-colour map with isolines on the model, its lux scale in the panel.

import * as api from './api.js';
import { toWorld } from './luminaires.js';

const $ = (id) => document.getElementById(id);
// The rows of the lux scale under each map the server draws (restauro_image::false_colour).
const LEGEND_PX = 36;
const VIRIDIS = [[68, 1, 84], [71, 45, 123], [59, 82, 139], [44, 114, 142], [33, 145, 140], [40, 174, 128], [94, 201, 98], [173, 220, 48], [253, 231, 37]];
// At most so many points from a face (the server allows more; a face's points are sent).
const MAX_FACE_POINTS = 5000;

let ctx = null;
let view = null;
let first = null;
// The last calculation: {revision, job, grids: Map name → GridResult}.
let computed = null;

// `context`: { edit(change) → Promise<view> (throws the server's words), picked() →
// {point, normal} | null, viewer() → Viewer | null, scene() → id }.
export function init(context) {
  ctx = context;
  $('grid-first').addEventListener('click', setFirst);
  $('grid-form').addEventListener('submit', (e) => { e.preventDefault(); addRectangle(); });
  $('grid-face').addEventListener('click', addFace);
  $('grid-compute').addEventListener('click', compute);
}

const fail = (e) => { $('grid-error').textContent = e.message || String(e); };
const fixed = (v, digits) => (Number.isFinite(v) ? v.toFixed(digits) : '–');

// The spacing as typed: a number, or the text itself for the server to refuse by name.
function spacing() {
  const text = $('grid-spacing').value;
  const n = Number(text);
  return text !== '' && Number.isFinite(n) ? n : text;
}

function setFirst() {
  const p = ctx.picked();
  if (!p || !p.normal) return fail(new Error('click a surface in the view first'));
  first = p;
  $('grid-error').textContent = '';
  $('grid-corners').textContent = `First corner at ${toWorld(p.point, view.offset_m).map((v) => v.toFixed(2)).join(', ')} m; click the opposite corner.`;
}

// Two directions along the plane of normal `n` (the preview's frame, Y up), e1 × e2 = n: on
// a floor or a ceiling e1 runs along x; on a wall it is level and e2 climbs.
function basis(n) {
  const N = new Float64Array(n);
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const unit = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
  const e1 = Math.abs(N[1]) > 0.7 ? unit([1 - N[0] * N[0], -N[0] * N[1], -N[0] * N[2]]) : unit(cross([0, 1, 0], n));
  return [e1, cross(n, e1)];
}

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const along = (p, d, s) => p.map((x, k) => x + s * d[k]);
const lift = () => Number($('grid-lift').value) || 0;

async function save(grid, spacing_m) {
  $('grid-error').textContent = '';
  try {
    const change = { edit: 'save-grid', grid };
    if (spacing_m !== undefined) change.spacing_m = spacing_m;
    await ctx.edit(change);
    return true;
  } catch (e) {
    fail(e);
    return false;
  }
}

async function addRectangle() {
  const p = ctx.picked();
  if (!first) return fail(new Error('set the first corner first: click a surface, then "First corner at the point clicked"'));
  if (!p) return fail(new Error('click the opposite corner in the view'));
  const n = first.normal;
  const [e1, e2] = basis(n);
  const d = p.point.map((x, k) => x - first.point[k]);
  const [a, b] = [dot(d, e1), dot(d, e2)];
  let origin = along(along(first.point, e1, Math.min(a, 0)), e2, Math.min(b, 0));
  origin = along(origin, n, lift());
  const u = e1.map((x) => x * Math.abs(a));
  const v = e2.map((x) => x * Math.abs(b));
  const grid = { name: $('grid-name').value, origin: toWorld(origin, view.offset_m), u: toWorld(u, [0, 0, 0]), v: toWorld(v, [0, 0, 0]) };
  if (await save(grid, spacing())) { first = null; $('grid-corners').textContent = 'No corner set.'; }
}

// The points, `step` apart, of the flat face under the last click: every triangle of the mesh
// clicked in the plane of the one clicked, sampled on a lattice of that plane.
function facePoints(hit, normal, step) {
  const mesh = hit.object;
  const position = mesh.geometry.getAttribute('position');
  const index = mesh.geometry.index;
  const count = index ? index.count : position.count;
  const at = (i) => {
    const k = index ? index.getX(i) : i;
    const m = mesh.matrixWorld.elements;
    const [x, y, z] = [position.getX(k), position.getY(k), position.getZ(k)];
    return [m[0] * x + m[4] * y + m[8] * z + m[12], m[1] * x + m[5] * y + m[9] * z + m[13], m[2] * x + m[6] * y + m[10] * z + m[14]];
  };
  const o = hit.point.toArray();
  const [e1, e2] = basis(normal);
  const flat = (p) => { const d = p.map((x, k) => x - o[k]); return [dot(d, e1), dot(d, e2), dot(d, normal)]; };
  const tolerance = 1e-3 * Math.max(step, 1);
  const triangles = [];
  for (let i = 0; i + 2 < count; i += 3) {
    const t = [flat(at(i)), flat(at(i + 1)), flat(at(i + 2))];
    if (t.every((q) => Math.abs(q[2]) < tolerance)) triangles.push(t);
  }
  const inside = (x, y, [a, b, c]) => {
    const s = (p, q) => (x - q[0]) * (p[1] - q[1]) - (p[0] - q[0]) * (y - q[1]);
    const [d1, d2, d3] = [s(a, b), s(b, c), s(c, a)];
    return !((d1 < 0 || d2 < 0 || d3 < 0) && (d1 > 0 || d2 > 0 || d3 > 0));
  };
  const xs = triangles.flat().map((q) => q[0]);
  const ys = triangles.flat().map((q) => q[1]);
  const points = [];
  for (let x = Math.min(...xs) + step / 2; x < Math.max(...xs); x += step) {
    for (let y = Math.min(...ys) + step / 2; y < Math.max(...ys); y += step) {
      if (!triangles.some((t) => inside(x, y, t))) continue;
      points.push(along(along(along(o, e1, x), e2, y), normal, lift()));
      if (points.length > MAX_FACE_POINTS) return null;
    }
  }
  return points;
}

async function addFace() {
  const p = ctx.picked();
  const viewer = ctx.viewer();
  if (!p || !p.normal || !viewer || !viewer.hit) return fail(new Error('click a surface in the view first'));
  const step = spacing();
  if (typeof step !== 'number' || !(step > 0)) {
    // The server's words for a spacing it cannot take, as a rectangle would have them.
    return save({ name: $('grid-name').value, origin: [0, 0, 0], u: [1, 0, 0], v: [0, 1, 0] }, step);
  }
  const points = facePoints(viewer.hit, p.normal, step);
  if (points === null) return fail(new Error(`spacing_m: more than ${MAX_FACE_POINTS} points on this face; give a larger spacing`));
  if (points.length === 0) return fail(new Error('spacing_m: no point of the lattice falls on this face; give a smaller spacing'));
  const grid = {
    name: $('grid-name').value,
    points: points.map((q) => toWorld(q, view.offset_m)),
    normal: toWorld(p.normal, [0, 0, 0]),
  };
  await save(grid);
}

async function compute() {
  if (!view) return;
  $('grid-error').textContent = '';
  const spp = $('grid-spp').value;
  const render = spp === '' ? {} : { samples_per_pixel: Number(spp) };
  const revision = view.revision;
  try {
    let job = await api.computeGrids(ctx.scene(), revision, render);
    $('grid-status').textContent = `computing the grids of revision ${revision} on the farm (job ${job.id})…`;
    while (!['done', 'failed', 'cancelled'].includes(job.state)) {
      await new Promise((r) => setTimeout(r, 400));
      job = await api.job(job.id);
    }
    if (job.state !== 'done') throw new Error(`the calculation ${job.state}: ${job.error || ''}`);
    const document = await api.illuminance(job.id);
    computed = { revision, job: job.id, grids: new Map(document.grids.map((g) => [g.name, g])) };
    $('grid-status').textContent = `computed: revision ${revision}, job ${job.id}.`;
    show(view);
  } catch (e) {
    $('grid-status').textContent = '';
    fail(e);
  }
}

// The false-colour colour of `lux` on a scale from 0 to `top` in ten bands (linear sRGB 0–1).
function colour(lux, top) {
  const t = Math.min(Math.max(lux / top, 0), 0.999);
  const s = (Math.floor(t * 10) + 0.5) / 10 * 8;
  const [i, f] = [Math.min(Math.floor(s), 7), s - Math.min(Math.floor(s), 7)];
  return VIRIDIS[i].map((c, k) => ((c + f * (VIRIDIS[i + 1][k] - c)) / 255) ** 2.2);
}

// The top of the server's scale: the maximum rounded up to a step of 1, 2 or 5 × 10^k.
function top(max) {
  if (!(max > 0)) return 1;
  const v = max / 10;
  const p = 10 ** Math.floor(Math.log10(v));
  const step = [1, 2, 5, 10].map((m) => m * p).find((x) => x >= v * (1 - 1e-12));
  return Math.ceil(max / step) * step;
}

// What the viewer draws of grid `name`'s calculation, when the revision shown was computed.
function result(name) {
  if (!computed || !view || computed.revision !== view.revision) return null;
  const g = computed.grids.get(name);
  if (!g) return null;
  return {
    url: api.illuminanceUrl(computed.job, `${name}.png`),
    legendPx: LEGEND_PX,
    colours: g.points.map((p) => colour(p.lux, top(g.max_lux))),
    figures: g,
  };
}

// The grids of the revision `v`.
export function show(v) {
  view = v;
  $('no-grids').hidden = v.grids.length > 0;
  $('grids').querySelector('tbody').replaceChildren(...v.grids.map(row));
  const maps = v.grids.map((g) => [g, result(g.name)]).filter(([, r]) => r);
  $('grid-maps').replaceChildren(...maps.map(([g, r]) => figure(g, r)));
  const viewer = ctx.viewer();
  if (viewer && viewer.bounds) viewer.placeGrids(v.grids, result);
}

function figure(g, r) {
  const f = document.createElement('figure');
  f.className = 'grid-map';
  const img = document.createElement('img');
  img.src = r.url;
  img.alt = `grid ${g.name}: illuminance in false colour with isolines, and its scale in lux`;
  const caption = document.createElement('figcaption');
  const x = r.figures;
  caption.textContent = `${g.name}: min ${fixed(x.min_lux, 4)} lx, mean ${fixed(x.mean_lux, 4)} lx, max ${fixed(x.max_lux, 4)} lx, U0 ${fixed(x.uniformity, 3)}`;
  f.append(img, caption);
  return f;
}

function row(g) {
  const tr = document.createElement('tr');
  tr.dataset.grid = g.name;
  const r = result(g.name);
  const x = r ? r.figures : null;
  const cells = [g.name, g.point_count, x ? fixed(x.min_lux, 4) : '–', x ? fixed(x.mean_lux, 4) : '–',
    x ? fixed(x.max_lux, 4) : '–', x ? fixed(x.uniformity, 3) : '–'];
  for (const c of cells) {
    const td = document.createElement('td');
    td.textContent = String(c);
    tr.append(td);
  }
  const td = document.createElement('td');
  const rename = document.createElement('button');
  rename.type = 'button';
  rename.textContent = 'Rename';
  rename.title = 'Gives this grid the name typed in the form below';
  rename.setAttribute('aria-label', `Rename grid ${g.name} to the name in the form`);
  rename.addEventListener('click', () => edit({ edit: 'rename-grid', name: g.name, to: $('grid-name').value }));
  const remove = document.createElement('button');
  remove.type = 'button';
  remove.textContent = 'Delete';
  remove.title = 'Removes this grid from the scene (a new revision)';
  remove.setAttribute('aria-label', `Delete grid ${g.name}`);
  remove.addEventListener('click', () => edit({ edit: 'delete-grid', name: g.name }));
  td.append(rename, ' ', remove);
  tr.append(td);
  return tr;
}

async function edit(change) {
  $('grid-error').textContent = '';
  try { await ctx.edit(change); } catch (e) { fail(e); }
}
