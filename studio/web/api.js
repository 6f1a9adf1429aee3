// The studio's calls to its coordinator. Every failure becomes an Error carrying the server's own
// words (the JSON body's `error`), which the page shows as they are.

export class ServerError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

export async function call(method, path, body) {
  // Never from the browser's cache: the API's answers are the farm's state now. (Two identical
  // requests at once otherwise wait on the cache's lock for the first one, tens of seconds in
  // Chromium.)
  const init = { method, credentials: 'same-origin', headers: {}, cache: 'no-store' };
  if (body instanceof ArrayBuffer) {
    init.headers['content-type'] = 'application/octet-stream';
    init.body = body;
  } else if (body !== undefined) {
    init.headers['content-type'] = 'application/json';
    init.body = JSON.stringify(body);
  }
  let response;
  try {
    response = await fetch(path, init);
  } catch (e) {
    throw new ServerError(0, `the coordinator cannot be reached (${e.message})`);
  }
  if (response.status === 204) return null;
  const text = await response.text();
  let data = null;
  try { data = text ? JSON.parse(text) : null; } catch { data = null; }
  if (!response.ok) {
    const words = data && data.error ? data.error : `${response.status} ${response.statusText}`;
    throw new ServerError(response.status, words);
  }
  return data;
}

export const signIn = (token) => call('POST', '/api/session', { token });
export const signOut = () => call('DELETE', '/api/session');
export const whoami = () => call('GET', '/api/whoami');
export const openDemo = () => call('POST', '/api/scenes/demo');
export const cancelJob = (id) => call('POST', `/api/jobs/${encodeURIComponent(id)}/cancel`);
export const resultUrl = (id, name) =>
  `/api/jobs/${encodeURIComponent(id)}/results/${encodeURIComponent(name)}`;
export const scenes = () => call('GET', '/api/scenes');
const sceneUrl = (id) => `/api/scenes/${encodeURIComponent(id)}`;
const at = (revision) => (revision === undefined || revision === null ? '' : `?revision=${revision}`);
export const scene = (id, revision) => call('GET', `${sceneUrl(id)}${at(revision)}`);
export const sceneGlbUrl = (id, revision) => `${sceneUrl(id)}/preview.glb${at(revision)}`;
// One edit of the scene (restauro_scene::edit::Edit as JSON); the new revision's view.
export const edit = (id, change) => call('POST', `${sceneUrl(id)}/edits`, change);
// A photometric file (IES or EULUMDAT, an ArrayBuffer) read and kept by the server: its
// reference and what it says.
export const uploadPhotometry = (id, name, bytes) =>
  call('POST', `${sceneUrl(id)}/photometry?name=${encodeURIComponent(name)}`, bytes);
// A scene folder as one tar (an ArrayBuffer): its preview job and the scene's id.
export const openFolder = (name, bytes, scene) => call('POST',
  `/api/scenes?${new URLSearchParams(scene ? { name, scene } : { name })}`, bytes);
// A measured reflectance (CSV, an ArrayBuffer) read and kept by the server: its reference, curve
// and colour.
export const uploadSpectrum = (id, name, bytes) =>
  call('POST', `${sceneUrl(id)}/spectrum?name=${encodeURIComponent(name)}`, bytes);
// An image (PNG or JPEG, an ArrayBuffer) for a note, checked and kept by the server: its
// reference, and where the page shows it from.
export const uploadImage = (id, name, bytes) =>
  call('POST', `${sceneUrl(id)}/images?name=${encodeURIComponent(name)}`, bytes);
export const imageUrl = (reference) => `/api/images/${encodeURIComponent(reference)}`;
export const revert = (id, revision) => call('POST', `${sceneUrl(id)}/revert`, { revision });
export const downloadUrl = (id, revision) => `${sceneUrl(id)}/download${at(revision)}`;
export const revisions = (id) => call('GET', `${sceneUrl(id)}/revisions`);
export const spectra = () => call('GET', '/api/spectra');
export const sunPath = (site) => call('GET', `/api/sun-path?${new URLSearchParams(site)}`);
export const takeSnapshot = (id, request) =>
  call('POST', `/api/scenes/${encodeURIComponent(id)}/snapshots`, request);
// A sun study or a walk (the server expands its frames), one job per hypothesis: the jobs and
// the frames' labels.
export const startSequence = (id, request) =>
  call('POST', `/api/scenes/${encodeURIComponent(id)}/sequences`, request);
// A sequence's frames from frame `from` on: each one's label, and its files once it is ready.
export const sequenceFrames = (job, from) =>
  call('GET', `/api/jobs/${encodeURIComponent(job)}/frames?from=${from}`);
const pair = (a, b) => `a=${encodeURIComponent(a)}&b=${encodeURIComponent(b)}`;
export const compare = (a, b) => call('GET', `/api/compare?${pair(a, b)}`);
export const compareMapUrl = (a, b) => `/api/compare/delta-e.png?${pair(a, b)}`;
// The revision's calculation grids computed on the farm (`render`: its options): the job.
export const computeGrids = (id, revision, render) =>
  call('POST', `${sceneUrl(id)}/grids`, { revision, render });
export const job = (id) => call('GET', `/api/jobs/${encodeURIComponent(id)}`);
// A finished calculation's figures per grid (`restauro illuminance`'s illuminance.json).
export const illuminance = (job) => call('GET', `/api/jobs/${encodeURIComponent(job)}/illuminance`);
export const illuminanceUrl = (job, name) =>
  `/api/jobs/${encodeURIComponent(job)}/illuminance/${encodeURIComponent(name)}`;
