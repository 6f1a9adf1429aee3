// What each control of the side bar's light and snapshot forms does, shown on hover (its
// `title`), by the control's id: one table, so that a control's help is found and kept in one
// place. A control whose markup carries its own title keeps it.

const HELP = {
  'lum-kind': 'A spot (a cone of light) or a point (all round, or as its photometric file says)',
  'lum-spectrum': "The luminaire's spectral power distribution (its lamp's spectrum)",
  'lum-x': 'Where the luminaire stands: x, metres east in the scene\'s frame',
  'lum-y': 'Where the luminaire stands: y, metres north in the scene\'s frame',
  'lum-z': 'Where the luminaire stands: z, metres up in the scene\'s frame',
  'lum-lift': 'How far off the surface clicked the luminaire is placed, in metres along its normal',
  'lum-place': 'Put the luminaire at the point clicked last, raised off the surface by the distance given',
  'lum-ax': 'The point the luminaire aims at: x, metres east',
  'lum-ay': 'The point the luminaire aims at: y, metres north',
  'lum-az': 'The point the luminaire aims at: z, metres up',
  'lum-aim': 'Aim the luminaire at the point clicked last',
  'lum-cd': 'Its peak luminous intensity in candela (scales a photometric file\'s own)',
  'lum-lm': 'Or its whole luminous flux in lumen, as a data sheet gives it',
  'lum-cone': "The beam's half-angle in degrees: full intensity inside it",
  'lum-falloff': 'Degrees beyond the cone over which the intensity falls to zero',
  'lum-file': 'A photometric file (IES LM-63 .ies or EULUMDAT .ldt) giving its intensity in every direction',
  'lum-file-clear': 'Use no photometric file: the cone or an even light all round',
  'lum-save': 'Add the luminaire to the scene (a new revision)',
  'lum-new': 'Leave the luminaire being edited and start a new one',
  'snap-width': 'The snapshot\'s width in pixels',
  'snap-height': 'The snapshot\'s height in pixels',
  'snap-spp': 'Light paths traced per pixel, the most a pixel takes under a noise target: more give less noise and take longer',
  'snap-noise': 'Each pixel stops once its own samples say its noise is below this share of its luminance, so quiet pixels (sky, sunlit stone) finish early; 0 traces every sample everywhere',
  'snap-integrator': 'How light is traced: path (light between surfaces too) or Whitted (direct light, as the paper)',
  'take-snapshot': 'Render this view on the farm, accurately, in the hypothesis chosen',
  'compare-a': 'The snapshot before (A)',
  'compare-b': 'The snapshot after (B)',
  'compare-go': 'Show A and B over the view, with a slider between them and their CIEDE2000 difference',
};

// Sets the help of every control in the table that has none of its own.
export function init() {
  for (const [id, text] of Object.entries(HELP)) {
    const control = document.getElementById(id);
    if (control && !control.title) control.title = text;
  }
}
