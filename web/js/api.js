// The voxd HTTP API as the page uses it: every error answer becomes an
// ApiError carrying the problem's title and detail (RFC 9457), which the
// page shows as it is.

export class ApiError extends Error {
  constructor(status, problem) {
    super(`${problem.title}: ${problem.detail}`);
    this.status = status;
    this.title = problem.title;
    this.detail = problem.detail;
  }
}

const KEY_STORE = 'voxd.apiKey';
export const apiKey = {
  get: () => localStorage.getItem(KEY_STORE) || '',
  set: (k) => (k ? localStorage.setItem(KEY_STORE, k) : localStorage.removeItem(KEY_STORE)),
};

function headers(extra = {}) {
  const key = apiKey.get();
  return key ? { ...extra, Authorization: `Bearer ${key}` } : extra;
}

async function problemOf(res) {
  const text = await res.text();
  try {
    const p = JSON.parse(text);
    if (p && typeof p.title === 'string') return p;
  } catch { /* not a problem document */ }
  return { title: `HTTP ${res.status}`, detail: text || res.statusText };
}

// fetch, with the API key, throwing ApiError on an error status.
export async function call(url, options = {}) {
  let res;
  try {
    res = await fetch(url, { ...options, headers: headers(options.headers) });
  } catch (e) {
    throw new ApiError(0, { title: 'The service cannot be reached', detail: String(e.message || e) });
  }
  if (!res.ok) throw new ApiError(res.status, await problemOf(res));
  return res;
}

export const getJson = async (url) => (await call(url)).json();

export async function submitJob(file, params) {
  const form = new FormData();
  form.append('mesh', file, file.name);
  form.append('params', new Blob([JSON.stringify(params)], { type: 'application/json' }));
  return (await call('/v1/jobs', { method: 'POST', body: form })).json();
}

export const listJobs = () => getJson('/v1/jobs?limit=20');
export const removeJob = (id) => call(`/v1/jobs/${id}`, { method: 'DELETE' });

// The job's server-sent events (GET /v1/jobs/{id}/events): `on` maps event
// names (job, state, progress, analysis, end, gone) to handlers of their
// parsed data. EventSource cannot send an Authorization header, so with an
// API key the stream is read through fetch. Returns a function that stops it.
export function watchJob(id, on) {
  const url = `/v1/jobs/${id}/events`;
  const dispatch = (name, data) => on[name] && on[name](JSON.parse(data));
  if (!apiKey.get()) {
    const source = new EventSource(url);
    for (const name of ['job', 'state', 'progress', 'analysis', 'end', 'gone']) {
      source.addEventListener(name, (e) => {
        if (name === 'end' || name === 'gone') source.close();
        dispatch(name, e.data);
      });
    }
    source.onerror = () => { if (source.readyState === EventSource.CLOSED && on.error) on.error(); };
    return () => source.close();
  }
  const abort = new AbortController();
  (async () => {
    const res = await call(url, { signal: abort.signal });
    const reader = res.body.pipeThrough(new TextDecoderStream()).getReader();
    let buffer = '';
    for (;;) {
      const { value, done } = await reader.read();
      if (done) return;
      buffer += value;
      let cut;
      while ((cut = buffer.indexOf('\n\n')) >= 0) {
        const block = buffer.slice(0, cut);
        buffer = buffer.slice(cut + 2);
        let name = 'message', data = '';
        for (const line of block.split('\n')) {
          if (line.startsWith('event: ')) name = line.slice(7);
          else if (line.startsWith('data: ')) data += line.slice(6);
        }
        if (data) dispatch(name, data);
      }
    }
  })().catch((e) => { if (e.name !== 'AbortError' && on.error) on.error(e); });
  return () => abort.abort();
}
