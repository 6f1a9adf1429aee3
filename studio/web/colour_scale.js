// A colour scale for the studio's maps: a viridis bar (the server's maps use the same nine
// anchors of matplotlib's viridis) with labels under it at positions 0–1.

const NS = 'http://www.w3.org/2000/svg';
const VIRIDIS = ['#440154', '#472d7b', '#3b528b', '#2c728e', '#21918c', '#28ae80', '#5ec962', '#addc30', '#fde725'];

function element(name, attributes) {
  const e = document.createElementNS(NS, name);
  for (const [k, v] of Object.entries(attributes)) e.setAttribute(k, v);
  return e;
}

// The bar, `label` read aloud, each of `ticks` ({at: 0–1, text}) written under it.
export function viridisScale(id, label, ticks) {
  const [w, h] = [360, 52];
  const svg = element('svg', { viewBox: `0 0 ${w} ${h}`, role: 'img', 'aria-label': label, class: 'delta-scale' });
  const grad = element('linearGradient', { id });
  VIRIDIS.forEach((c, i) => grad.append(element('stop', { offset: `${(i / 8) * 100}%`, 'stop-color': c })));
  const defs = element('defs', {});
  defs.append(grad);
  svg.append(defs, element('rect', { x: 10, y: 4, width: w - 20, height: 16, fill: `url(#${id})` }));
  for (const { at, text, y = 34 } of ticks) {
    const x = 10 + at * (w - 20);
    const anchor = x < 30 ? 'start' : x > w - 30 ? 'end' : 'middle';
    const t = element('text', { x, y, 'text-anchor': anchor });
    t.textContent = text;
    svg.append(t);
  }
  return svg;
}
