// The history of snapshots: a strip of thumbnails along the bottom of the view, oldest first.
// A thumbnail shows its snapshot as the layer over the view; its A and B buttons choose it for
// the comparison (the same choice as the pickers in panel 5). The thumbnail is the farm's PNG
// scaled by the browser: the layer shows that very file, so it is fetched once for both, and
// the server keeps no second picture of each snapshot.

import * as api from './api.js';
import * as farm from './farm.js';

const $ = (id) => document.getElementById(id);
let onShow = () => {};

const png = (job) => job.results.find((n) => n.endsWith('.png') && !n.endsWith('-retinex.png'));

function button(text, label, title, onClick) {
  const b = document.createElement('button');
  b.type = 'button';
  b.textContent = text;
  b.setAttribute('aria-label', label);
  b.title = title;
  b.addEventListener('click', onClick);
  return b;
}

// Which thumbnails are A and B (the pickers' choice).
function marks() {
  for (const li of $('strip-list').children) {
    for (const side of ['a', 'b']) {
      li.querySelector(`.pick-${side}`).setAttribute('aria-pressed', String($(`compare-${side}`).value === li.dataset.job));
    }
  }
}

function choose(side, id) {
  const picker = $(`compare-${side}`);
  picker.value = id;
  picker.dispatchEvent(new Event('change'));
}

function item(j) {
  const li = document.createElement('li');
  li.dataset.job = j.id;
  const img = document.createElement('img');
  img.src = api.resultUrl(j.id, png(j));
  img.alt = '';
  const name = document.createElement('span');
  name.textContent = j.name;
  const show = button('', `Show ${j.name} over the view`, `Show ${j.name} (${j.width} × ${j.height} px) over the view, at its camera`, () => onShow(farm.jobById(j.id) || j));
  show.className = 'thumb';
  show.append(img, name);
  const a = button('A', `${j.name} as A (before)`, 'Compare from this snapshot: A, before', () => choose('a', j.id));
  const b = button('B', `${j.name} as B (after)`, 'Compare with this snapshot: B, after', () => choose('b', j.id));
  a.className = 'pick-a';
  b.className = 'pick-b';
  li.append(show, a, b);
  return li;
}

// The strip as the farm's finished snapshots stand.
export function refresh() {
  const done = farm.doneJobs().filter(png);
  const list = $('strip-list');
  const kept = new Map([...list.children].map((li) => [li.dataset.job, li]));
  list.replaceChildren(...done.map((j) => kept.get(j.id) || item(j)));
  $('snapshot-strip').hidden = done.length === 0;
  $('stage').classList.toggle('with-strip', done.length > 0);
  marks();
}

export function init({ show, compare }) {
  onShow = show;
  for (const side of ['a', 'b']) $(`compare-${side}`).addEventListener('change', marks);
  $('strip-compare').addEventListener('click', compare);
}
