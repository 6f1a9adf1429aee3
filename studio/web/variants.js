// Hypotheses (the scene's `[variants.NAME]`): the one chosen colours the preview, each part in
// the state the hypothesis gives it (as the server resolves it, the render's rule), and is the
// one a snapshot renders. New, rename and delete are edits; so is setting the state of the part
// clicked, for that part or its whole object, from the material panel.

const $ = (id) => document.getElementById(id);
const STATES = ['base', 'degraded', 'cleaned'];
let ctx = null;

// `context`: { edit(change), error(e), changed(variant or null) }.
export function init(context) {
  ctx = context;
  $('snap-variant').addEventListener('change', () => ctx.changed(chosen()));
  $('new-variant').addEventListener('click', create);
  $('rename-variant').addEventListener('click', rename);
  $('delete-variant').addEventListener('click', remove);
}

let view = null;

// The hypothesis chosen, as the scene's view has it (null: as the scene is).
export function chosen() {
  const name = $('snap-variant').value;
  return (view && view.variants.find((v) => v.name === name)) || null;
}

// The picker filled from the revision `v`, keeping the choice while it exists.
export function show(v) {
  view = v;
  const picker = $('snap-variant');
  const was = picker.value;
  picker.replaceChildren(new Option('as the scene is', ''), ...v.variants.map((x) => new Option(x.name, x.name)));
  if (v.variants.some((x) => x.name === was)) picker.value = was;
  summarise();
}

// Chooses hypothesis `name` ('' for none), as if picked.
export function choose(name) {
  $('snap-variant').value = name;
  summarise();
  ctx.changed(chosen());
}

// The next hypothesis in the list (V).
export function next() {
  const picker = $('snap-variant');
  if (picker.options.length < 2) return;
  choose(picker.options[(picker.selectedIndex + 1) % picker.options.length].value);
}

function summarise() {
  const v = chosen();
  const parts = v ? Object.values(v.parts) : [];
  const count = (s) => parts.filter((p) => p === s).length;
  $('variant-summary').textContent = v
    ? `${v.name}: ${STATES.map((s) => `${count(s)} ${s}`).join(', ')} of ${parts.length} parts`
    : 'every part in its base state';
}

function nameGiven() {
  const name = $('variant-name').value.trim();
  if (!name) ctx.error(new Error('type the hypothesis\'s name in "Name" first'));
  return name;
}

async function create() {
  const name = nameGiven();
  if (!name) return;
  if (await ctx.edit({ edit: 'save-variant', name, state: $('variant-state').value, states: {} })) {
    choose(name);
    $('variant-name').value = '';
  }
}

async function rename() {
  const v = chosen();
  if (!v) return ctx.error(new Error('choose the hypothesis to rename first'));
  const to = nameGiven();
  if (!to) return;
  if (await ctx.edit({ edit: 'rename-variant', name: v.name, to })) {
    choose(to);
    $('variant-name').value = '';
  }
}

async function remove() {
  const v = chosen();
  if (!v) return ctx.error(new Error('choose the hypothesis to delete first'));
  if (await ctx.edit({ edit: 'delete-variant', name: v.name })) choose('');
}

// The controls, under the material panel, that set the state of the part `picked` in the
// chosen hypothesis: for the part alone or for its whole object.
export function partControls(picked) {
  const v = chosen();
  const box = document.createElement('form');
  box.className = 'variant-part';
  box.setAttribute('aria-label', 'This part in the hypothesis');
  if (!v) {
    box.innerHTML = '<p class="hint">Choose or create a hypothesis above to set this part\'s state in it.</p>';
    return box;
  }
  const key = `${picked.object}/${picked.part}`;
  const now = v.parts[key] || v.state;
  box.innerHTML = `<h4>In hypothesis “${v.name}”</h4>
    <p>This part is <strong id="part-state-now">${now}</strong>.</p>
    <label for="part-state">State</label>
    <select id="part-state">${STATES.map((s) => `<option value="${s}">${s}</option>`).join('')}</select>
    <button type="button" id="part-state-part">Set for this part</button>
    <button type="button" id="part-state-object">Set for the whole object</button>`;
  box.querySelector('#part-state').value = now;
  const set = (which) => {
    const state = box.querySelector('#part-state').value;
    const states = { ...v.states };
    if (which === 'object') {
      // The object's entry wins over the default, and its parts' own entries over it: they go.
      for (const k of Object.keys(states)) if (k.startsWith(`${picked.object}/`)) delete states[k];
      states[picked.object] = state;
    } else {
      states[key] = state;
    }
    ctx.edit({ edit: 'save-variant', name: v.name, state: v.state, states });
  };
  box.querySelector('#part-state-part').addEventListener('click', () => set('part'));
  box.querySelector('#part-state-object').addEventListener('click', () => set('object'));
  return box;
}
