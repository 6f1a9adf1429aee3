// Notes pinned to the model: each a pin in the view and an entry in the list, with its title,
// text and links; opening one flies to the pose kept with it. A note is pinned where the last
// click landed, and kept in the scene (a new revision), so it survives anything the page does.

const $ = (id) => document.getElementById(id);

let notes = [];
let onEdit = () => {};
let onOpen = () => {};

// The notes of the scene `view`, listed.
export function show(view) {
  notes = view.annotations;
  const list = $('notes-list');
  list.replaceChildren(...notes.map((n) => {
    const li = document.createElement('li');
    const b = document.createElement('button');
    b.type = 'button';
    b.textContent = n.title;
    b.dataset.note = n.title;
    b.addEventListener('click', () => open(n.title));
    li.append(b);
    return li;
  }));
  $('no-notes').hidden = notes.length > 0;
  const shown = $('note-shown').dataset.note;
  if (shown && !notes.some((n) => n.title === shown)) $('note-shown').hidden = true;
}

// Shows note `title` and flies to its pose.
export function open(title) {
  const n = notes.find((x) => x.title === title);
  if (!n) return;
  const panel = $('note-shown');
  panel.hidden = false;
  panel.dataset.note = n.title;
  $('note-title').textContent = n.title;
  $('note-part').textContent = n.part ? `About ${n.part}` : '';
  $('note-text').textContent = n.text;
  $('note-links').replaceChildren(...n.links.map((url) => {
    const li = document.createElement('li');
    const a = document.createElement('a');
    a.href = url;
    a.textContent = url;
    a.target = '_blank';
    a.rel = 'noopener noreferrer';
    li.append(a);
    return li;
  }));
  onOpen(n);
}

// `picked()` gives the surface last clicked ({object, part, point}) and `pose()` the camera.
export function init({ edit, fly, picked, pose }) {
  onEdit = edit;
  onOpen = (n) => fly(n);
  $('note-form').addEventListener('submit', (e) => {
    e.preventDefault();
    const at = picked();
    if (!at) { $('note-form-problem').textContent = 'click the surface the note is about first'; return; }
    $('note-form-problem').textContent = '';
    const annotation = {
      title: $('note-new-title').value.trim(),
      text: $('note-new-text').value,
      position: at.point,
      part: at.object && at.part ? `${at.object}/${at.part}` : null,
      links: $('note-new-links').value.split('\n').map((l) => l.trim()).filter(Boolean),
      pose: $('note-new-pose').checked ? pose() : null,
    };
    onEdit({ edit: 'save-annotation', annotation });
  });
  $('note-delete').addEventListener('click', () => {
    const title = $('note-shown').dataset.note;
    if (title) onEdit({ edit: 'delete-annotation', title });
  });
}
