// The side bar and its panels: each panel folds under its header (a button with
// aria-expanded), the whole side bar folds away (P) to give the view the whole window, and a
// panel's key (1–6) opens it and moves to it. What was folded is kept for the next visit. The
// snapshot and the comparison show over the view; the one shown last is in front, and each
// closes with its × or Esc.

const $ = (id) => document.getElementById(id);
const KEPT = 'restauro.studio.panels';
const OVERLAYS = ['result', 'compare-stage', 'sequence-stage'];

const heads = () => [...document.querySelectorAll('.panel-head button[aria-controls]')];

function remember() {
  try {
    const folded = heads().filter((b) => b.getAttribute('aria-expanded') === 'false').map((b) => b.dataset.key);
    localStorage.setItem(KEPT, JSON.stringify({ sidebar: sidebarOpen(), folded }));
  } catch { /* storage refused: nothing is kept */ }
}

export function sidebarOpen() {
  return !$('studio').classList.contains('folded');
}

// The side bar shown (true) or folded away (false).
export function showSidebar(on) {
  $('studio').classList.toggle('folded', !on);
  $('sidebar-toggle').setAttribute('aria-expanded', String(on));
  remember();
}

// The panel under header button `b` open (true) or folded (false).
function setPanel(b, open) {
  b.setAttribute('aria-expanded', String(open));
  b.title = `${open ? 'Fold' : 'Open'} this panel (${b.dataset.key})`;
  $(b.getAttribute('aria-controls')).hidden = !open;
  remember();
}

const head = (key) => heads().find((b) => b.dataset.key === String(key));

// Panel `key` (1–6) opened; with `reveal`, the side bar too, scrolled to it and its header
// focused.
export function open(key, reveal) {
  const b = head(key);
  if (!b) return;
  if (b.getAttribute('aria-expanded') !== 'true') setPanel(b, true);
  if (reveal && !sidebarOpen()) showSidebar(true);
  if (sidebarOpen()) b.closest('.panel').scrollIntoView({ block: reveal ? 'start' : 'nearest' });
  if (reveal) b.focus({ preventScroll: true });
}

// Whether header `b` is in the side bar's sight (not scrolled away, nor under another panel's
// header stuck at the top).
function inSight(b) {
  const p = $('panels').getBoundingClientRect();
  const r = b.closest('.panel').getBoundingClientRect();
  return r.top >= p.top - 1 && r.top + b.offsetHeight <= p.bottom;
}

// A panel's key: opens it and moves to it, or folds it when it is open and in sight already.
export function key(k) {
  const b = head(k);
  if (!b) return false;
  if (sidebarOpen() && b.getAttribute('aria-expanded') === 'true' && inSight(b)) setPanel(b, false);
  else open(k, true);
  return true;
}

// The overlay shown in front, if any.
function front() {
  const shown = OVERLAYS.map($).filter((o) => !o.hidden);
  return shown.find((o) => o.classList.contains('front')) || shown[0] || null;
}

function raise(o) {
  for (const other of OVERLAYS.map($)) other.classList.toggle('front', other === o);
}

// Closes overlay `o`; it is told with a `close` event.
function close(o) {
  o.hidden = true;
  o.classList.remove('front');
  o.dispatchEvent(new Event('close'));
}

// Esc: the overlay in front closes. True when one did.
export function closeFront() {
  const o = front();
  if (!o) return false;
  close(o);
  return true;
}

export function init() {
  let kept = null;
  try { kept = JSON.parse(localStorage.getItem(KEPT) || 'null'); } catch { kept = null; }
  for (const b of heads()) {
    b.title = `Fold this panel (${b.dataset.key})`;
    b.addEventListener('click', () => setPanel(b, b.getAttribute('aria-expanded') !== 'true'));
    if (kept && kept.folded.includes(b.dataset.key)) setPanel(b, false);
  }
  if (kept && kept.sidebar === false) showSidebar(false);
  $('sidebar-toggle').addEventListener('click', () => showSidebar(!sidebarOpen()));
  // An overlay just shown comes to the front; a click in one brings it there.
  const watch = new MutationObserver((changes) => {
    for (const c of changes) if (!c.target.hidden) raise(c.target);
  });
  for (const o of OVERLAYS.map($)) {
    watch.observe(o, { attributes: true, attributeFilter: ['hidden'] });
    o.addEventListener('pointerdown', () => raise(o));
    o.querySelector('.overlay-close').addEventListener('click', () => close(o));
  }
}
