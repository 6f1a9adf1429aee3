// The studio's calls to its coordinator. Every failure becomes an Error carrying the server's own
// words (the JSON body's `error`), which the page shows as they are.

export class ServerError extends Error {
  constructor(status, message) {
    super(message);
    this.status = status;
  }
}

export async function call(method, path, body) {
  const init = { method, credentials: 'same-origin', headers: {} };
  if (body !== undefined) {
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
export const cancelJob = (id) => call('POST', `/api/jobs/${encodeURIComponent(id)}/cancel`);
export const resultUrl = (id, name) =>
  `/api/jobs/${encodeURIComponent(id)}/results/${encodeURIComponent(name)}`;
export const scenes = () => call('GET', '/api/scenes');
export const scene = (id) => call('GET', `/api/scenes/${encodeURIComponent(id)}`);
export const sceneGlbUrl = (id) => `/api/scenes/${encodeURIComponent(id)}/preview.glb`;
export const takeSnapshot = (id, request) =>
  call('POST', `/api/scenes/${encodeURIComponent(id)}/snapshots`, request);
