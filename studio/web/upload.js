// A scene folder sent to the coordinator: the folder a person picks (its files with their
// paths in it) is packed here into one POSIX tar (IEEE 1003.1 ustar) and posted; or a tar or zip
// made elsewhere (the studio's own download, `restauro scene bundle --out`, a file manager's
// "compress") is posted as it is. The
// server bundles and checks it as the command line does and renders a quick preview of it; the
// page then opens it.

import * as api from './api.js';

const $ = (id) => document.getElementById(id);
const BLOCK = 512;
let ctx = null;

// A ustar header field: `text` as bytes at `offset`, at most `length`.
function field(header, offset, length, text) {
  const bytes = new TextEncoder().encode(text);
  if (bytes.length > length) throw new Error(`"${text}" is too long for a tar header`);
  header.set(bytes, offset);
}

const octal = (value, length) => value.toString(8).padStart(length - 1, '0');

// One tar of `files` ([{ name: 'folder/scene.toml', bytes: Uint8Array }]), each a regular file.
export function tarOf(files) {
  const parts = [];
  for (const { name, bytes } of files) {
    const header = new Uint8Array(BLOCK);
    const encoded = new TextEncoder().encode(name);
    let [prefix, rest] = ['', name];
    if (encoded.length > 100) {
      // ustar splits a long path at a `/` into a prefix (155 bytes) and a name (100).
      const cut = name.lastIndexOf('/', name.length - 1);
      [prefix, rest] = [name.slice(0, cut), name.slice(cut + 1)];
    }
    field(header, 0, 100, rest);
    field(header, 100, 8, '0000644');
    field(header, 108, 8, '0000000');
    field(header, 116, 8, '0000000');
    field(header, 124, 12, octal(bytes.length, 12));
    field(header, 136, 12, octal(Math.floor(Date.now() / 1000), 12));
    field(header, 148, 8, '        ');
    field(header, 156, 1, '0');
    field(header, 257, 6, 'ustar');
    field(header, 263, 2, '00');
    field(header, 345, 155, prefix);
    const sum = header.reduce((s, b) => s + b, 0);
    field(header, 148, 8, `${octal(sum, 7)}\0`);
    parts.push(header, bytes, new Uint8Array((BLOCK - (bytes.length % BLOCK)) % BLOCK));
  }
  parts.push(new Uint8Array(2 * BLOCK));
  const out = new Uint8Array(parts.reduce((n, p) => n + p.length, 0));
  let at = 0;
  for (const p of parts) { out.set(p, at); at += p.length; }
  return out;
}

async function send(name, bytes, scene) {
  $('upload-status').textContent = `sending ${name} (${(bytes.byteLength / 1e6).toFixed(1)} MB)…`;
  try {
    const opened = await api.openFolder(name, bytes, scene);
    $('upload-status').textContent = `${name}: its preview is rendering`;
    $('open-folder-dialog').close();
    await ctx.opened(opened);
  } catch (e) {
    $('upload-status').textContent = '';
    ctx.error(e);
    $('upload-problem').textContent = e.message;
  }
}

// A job name from a file or folder name: letters, digits, `-` and `_`.
const stem = (name) => (name.replace(/\.(tar|zip)$/i, '').replace(/[^A-Za-z0-9_-]+/g, '-').replace(/^-+|-+$/g, '') || 'scene');

async function folderChosen() {
  const files = [...$('upload-folder').files];
  if (files.length === 0) return;
  const read = await Promise.all(files.map(async (f) => ({
    name: f.webkitRelativePath || f.name,
    bytes: new Uint8Array(await f.arrayBuffer()),
  })));
  const top = read[0].name.split('/')[0];
  // A folder with several scene files at its top level: the person chooses one.
  const depth = (n) => n.split('/').length;
  const scenes = read.map((f) => f.name).filter((n) => n.endsWith('.toml'));
  const shallowest = Math.min(...scenes.map(depth));
  const choices = scenes.filter((n) => depth(n) === shallowest).sort();
  prepared = { name: stem(top), bytes: tarOf(read).buffer };
  if (choices.length > 1) {
    $('upload-scene').replaceChildren(...choices.map((n) => new Option(n, n)));
    $('upload-choose').hidden = false;
    $('upload-status').textContent = `${choices.length} scene files in ${top}: choose one and send it`;
    return;
  }
  await send(prepared.name, prepared.bytes);
}

let prepared = null;

async function archiveChosen() {
  const file = $('upload-archive').files[0];
  if (file) await send(stem(file.name), await file.arrayBuffer());
}

// `context`: { opened({job, scene}), error(e) }.
export function init(context) {
  ctx = context;
  for (const id of ['open-folder', 'welcome-open-folder']) {
    $(id).addEventListener('click', () => {
      $('upload-problem').textContent = '';
      $('upload-choose').hidden = true;
      $('open-folder-dialog').showModal();
    });
  }
  $('upload-folder').addEventListener('change', folderChosen);
  $('upload-archive').addEventListener('change', archiveChosen);
  $('upload-send').addEventListener('click', () => prepared && send(prepared.name, prepared.bytes, $('upload-scene').value));
}
