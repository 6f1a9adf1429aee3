// Which light the preview colours the materials under: the scene's own light (its daylight on
// the ground, or its luminaires' when it has none), one of its light spectra alone, or D65.
// The server computes each material's colour and L*a*b* under every one of them from the
// spectra; the page only chooses.

const $ = (id) => document.getElementById(id);

// The scene's choices, from its view; the one chosen is kept when the new view still has it.
export function show(view) {
  const picker = $('preview-light');
  const was = picker.value;
  picker.replaceChildren(...view.preview_lights.map((l) => new Option(l.label, l.key)));
  if (view.preview_lights.some((l) => l.key === was)) picker.value = was;
}

// The key of the light chosen (`scene` until the view is shown).
export function chosen() {
  return $('preview-light').value || 'scene';
}

// How the spectrum state `s` (a `StateView`) looks under the light chosen: {lab, colour_linear_srgb}.
export function look(s) {
  return (s.under && s.under[chosen()]) || s;
}

// The name of the light chosen, for labels.
export function name() {
  const o = $('preview-light').selectedOptions[0];
  return o ? o.textContent : 'D65';
}

export function init(changed) {
  $('preview-light').addEventListener('change', changed);
}
