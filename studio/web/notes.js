// Notes pinned to the model: each a pin in the view and an entry in the list, with its title,
// text, links and images; opening one flies to the pose kept with it. A note is pinned where the last
// click landed, and kept in the scene (a new revision), so it survives anything the page does.

const $ = (id) => document.getElementById(id);

let notes = [];
let onEdit = () => {};
let onOpen = () => {};
let send = async () => null;
let imageUrl = () => '';

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
  const panel = $('note-shown');
  const shown = notes.find((n) => n.title === panel.dataset.note);
  if (shown && !panel.hidden) render(shown);
  else panel.hidden = true;
}

// Shows note `title` and flies to its pose.
export function open(title) {
  const n = notes.find((x) => x.title === title);
  if (!n) return;
  render(n);
  onOpen(n);
}

// Note `n` in its panel.
function render(n) {
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
  $('note-images').replaceChildren(...(n.images || []).map((reference, k) => {
    const figure = document.createElement('figure');
    const a = document.createElement('a');
    a.href = imageUrl(reference);
    a.target = '_blank';
    a.rel = 'noopener noreferrer';
    const img = document.createElement('img');
    img.src = a.href;
    img.alt = `image ${k + 1} of the note “${n.title}” (opens full size)`;
    a.append(img);
    const remove = document.createElement('button');
    remove.type = 'button';
    remove.textContent = 'Remove';
    remove.setAttribute('aria-label', `remove image ${k + 1} from the note`);
    remove.addEventListener('click', () => resave(n, n.images.filter((_, i) => i !== k)));
    figure.append(a, remove);
    return figure;
  }));
}

// Saves note `n` again with `images` (its pin, text and links as they are).
function resave(n, images) {
  return onEdit({ edit: 'save-annotation', annotation: { ...n, images } });
}

// Sends each image chosen for the note; their references, or null when the server refused one
// (its words shown by `error`).
async function sendImages(input, error) {
  const references = [];
  for (const file of input.files) {
    $('note-form-problem').textContent = `sending ${file.name}…`;
    try {
      references.push((await send(file.name, await file.arrayBuffer())).reference);
    } catch (e) {
      $('note-form-problem').textContent = '';
      error(e);
      return null;
    }
  }
  $('note-form-problem').textContent = '';
  return references;
}

// `picked()` gives the surface last clicked ({object, part, point}) and `pose()` the camera;
// `upload(name, bytes)` keeps an image on the server and `url(reference)` shows it.
export function init({ edit, error, fly, picked, pose, upload, url }) {
  onEdit = edit;
  onOpen = (n) => fly(n);
  send = upload;
  imageUrl = url;
  $('note-form').addEventListener('submit', async (e) => {
    e.preventDefault();
    const at = picked();
    if (!at) { $('note-form-problem').textContent = 'click the surface the note is about first'; return; }
    $('note-form-problem').textContent = '';
    const images = await sendImages($('note-new-images'), error);
    if (!images) return;
    const annotation = {
      title: $('note-new-title').value.trim(),
      text: $('note-new-text').value,
      position: at.point,
      part: at.object && at.part ? `${at.object}/${at.part}` : null,
      links: $('note-new-links').value.split('\n').map((l) => l.trim()).filter(Boolean),
      images,
      pose: $('note-new-pose').checked ? pose() : null,
    };
    if (await onEdit({ edit: 'save-annotation', annotation })) $('note-new-images').value = '';
  });
  $('note-add-images').addEventListener('change', async () => {
    const n = notes.find((x) => x.title === $('note-shown').dataset.note);
    const added = n && await sendImages($('note-add-images'), error);
    $('note-add-images').value = '';
    if (added && added.length) await resave(n, [...(n.images || []), ...added]);
  });
  $('note-delete').addEventListener('click', () => {
    const title = $('note-shown').dataset.note;
    if (title) onEdit({ edit: 'delete-annotation', title });
  });
}
