// REST and WebSocket access to the roverplan server (server/api/routes.cpp): bearer token,
// JSON errors as ApiError {status, code, message, field}, raw float32 layers, XHR uploads.

const TOKEN_KEY = 'roverplan.token';

export class ApiError extends Error {
  constructor(status, code, message, field) {
    super(message || `HTTP ${status}`);
    this.status = status;
    this.code = code || '';
    this.field = field || '';
  }
  // "message (field: x)" for people.
  describe() {
    return this.field ? `${this.message} (field: ${this.field})` : this.message;
  }
}

export function getToken() {
  try { return localStorage.getItem(TOKEN_KEY) || ''; } catch { return ''; }
}

export function setToken(token) {
  try {
    if (token) localStorage.setItem(TOKEN_KEY, token);
    else localStorage.removeItem(TOKEN_KEY);
  } catch { /* storage disabled: the token lives for this page only */ }
  sessionToken = token;
}

let sessionToken = getToken();

// The operator's name (issue 26): typed once, kept in this browser, sent as X-Operator so the
// server's events and history say who did what (a named token's name wins on the server).
const OPERATOR_KEY = 'roverplan.operator';
let operatorName = (() => {
  try { return localStorage.getItem(OPERATOR_KEY) || ''; } catch { return ''; }
})();

export function getOperator() {
  return operatorName;
}

// Trimmed, at most 40 characters (the server's limit), printable only.
export function setOperator(name) {
  operatorName = String(name || '').replace(/[\u0000-\u001f\u007f\u200b-\u200f\u202a-\u202e\u2066-\u2069]/g, '').trim().slice(0, 40);
  try {
    if (operatorName) localStorage.setItem(OPERATOR_KEY, operatorName);
    else localStorage.removeItem(OPERATOR_KEY);
  } catch { /* storage disabled: the name lives for this page only */ }
  return operatorName;
}

function authHeaders(extra = {}) {
  const h = { ...extra };
  if (sessionToken) h.Authorization = `Bearer ${sessionToken}`;
  // fetch() sends a header's characters as bytes (U+0000–U+00FF only): a name is sent as its
  // UTF-8 bytes, which the server reads as UTF-8 ("Zoë" stays "Zoë").
  if (operatorName) h['X-Operator'] = String.fromCharCode(...new TextEncoder().encode(operatorName));
  return h;
}

async function errorFrom(response) {
  let body = null;
  try { body = await response.json(); } catch { /* not JSON */ }
  const e = body && body.error ? body.error : {};
  const err = new ApiError(response.status, e.code, e.message || `${response.status} ${response.statusText}`, e.field);
  // A 412 version_conflict carries the object as stored now (issue 26).
  if (e.current !== undefined) err.current = e.current;
  return err;
}

// fetch() with the token; throws ApiError on a non-2xx answer or a network failure.
export async function request(path, options = {}) {
  let response;
  try {
    response = await fetch(path, { ...options, headers: authHeaders(options.headers) });
  } catch (err) {
    if (err.name === 'AbortError') throw new ApiError(0, 'aborted', 'request cancelled', '');
    throw new ApiError(0, 'network', `cannot reach the server: ${err.message}`, '');
  }
  if (!response.ok) throw await errorFrom(response);
  return response;
}

export async function getJson(path) {
  return (await request(path)).json();
}

export async function sendJson(method, path, body, headers = {}) {
  const response = await request(path, {
    method,
    headers: { 'Content-Type': 'application/json', ...headers },
    body: body === undefined ? undefined : JSON.stringify(body),
  });
  return response.json();
}

// A paginated listing (server: ?limit=&offset=, the next page in a Link rel="next" header), all
// pages concatenated; at most `maxPages` requests of up to 500 items each.
export async function getAllPages(path, maxPages = 100) {
  const items = [];
  let next = `${path}${path.includes('?') ? '&' : '?'}limit=500`;
  for (let page = 0; next && page < maxPages; ++page) {
    const response = await request(next);
    items.push(...(await response.json()));
    const link = response.headers.get('Link') || '';
    const m = /<([^>]+)>\s*;\s*rel="next"/.exec(link);
    next = m ? m[1] : null;
  }
  return items;
}

// Versions (issue 26): a write names the version it was read at (If-Match), so a change saved
// meanwhile by another operator is answered 412 version_conflict (err.current: theirs) instead of
// being overwritten. The caller keeps the version its edits started from.
const ifMatch = (version) => (Number.isInteger(version) ? { 'If-Match': `"v${version}"` } : {});

// `version`: the set's version the edits started from (omitted: none, a first save).
function writeZones(mapId, fc, crs, version) {
  const body = { ...fc };
  delete body.version;  // the version read goes in If-Match
  return sendJson('PUT', `/api/maps/${mapId}/zones${crs === 'map' ? '?crs=map' : ''}`, body, ifMatch(version));
}

export const api = {
  health: () => getJson('/api/health'),
  planners: () => getJson('/api/planners'),
  // The planners with the defaults that come from one map (coverage cell, its body's gravity).
  plannersForMap: (mapId) => getJson(`/api/planners?map=${encodeURIComponent(mapId)}`),
  maps: () => getAllPages('/api/maps'),
  map: (id) => getJson(`/api/maps/${id}`),
  deleteMap: (id) => sendJson('DELETE', `/api/maps/${id}`),
  // `version`: the map's as read (412 with theirs when someone renamed it since).
  renameMap: (id, name, version) => sendJson('PATCH', `/api/maps/${id}`, { name }, ifMatch(version)),
  renameStudy: (id, name, version) => sendJson('PATCH', `/api/studies/${id}`, { name }, ifMatch(version)),
  pdms: (mapId) => getAllPages(`/api/maps/${mapId}/pdms`),
  createPdm: (mapId, body) => sendJson('POST', `/api/maps/${mapId}/pdms`, body),
  deletePdm: (mapId, pdmId) => sendJson('DELETE', `/api/maps/${mapId}/pdms/${pdmId}`),
  // A PDM's new name and/or components; 412 with theirs when `version` is not the stored one.
  changePdm: (mapId, pdmId, body, version) => sendJson('PUT', `/api/maps/${mapId}/pdms/${pdmId}`, body, ifMatch(version)),
  pdm: (mapId, pdmId) => getJson(`/api/maps/${mapId}/pdms/${pdmId}`),
  zones: (mapId) => getJson(`/api/maps/${mapId}/zones`),
  // 412 (err.code 'version_conflict') when another operator saved zones since `version`.
  saveZones: (mapId, fc, crs = 'local', version) => writeZones(mapId, fc, crs, version),
  // History (the last 50 versions): `what` is `zones` or `pdms/{id}`.
  history: (mapId, what) => getJson(`/api/maps/${mapId}/${what}/history`),
  historyVersion: (mapId, what, n) => getJson(`/api/maps/${mapId}/${what}/history/${n}`),
  restore: (mapId, what, n, version) => sendJson('POST', `/api/maps/${mapId}/${what}/restore`, { restore: n }, ifMatch(version)),
  missions: () => getAllPages('/api/missions'),
  mission: (id) => getJson(`/api/missions/${id}`),
  launch: (body) => sendJson('POST', '/api/missions', body),
  cancel: (id) => sendJson('DELETE', `/api/missions/${id}`),
  deleteMission: (id) => sendJson('DELETE', `/api/missions/${id}`),
  // `version`: the mission's as read (412 when someone relabelled it since).
  labelMission: (id, label, version) => sendJson('PATCH', `/api/missions/${id}`, { label }, ifMatch(version)),
  missionFile: (id) => request(`/api/missions/${id}/mission.json`).then((r) => r.json()),
  result: (id) => getJson(`/api/missions/${id}/result.json`),
};

// `version`: an edited PDM's (issue 26), so a file cached for an older version is not used.
export function layerUrl(mapId, name, format, { max = 0, pdm = '', version = 0 } = {}) {
  const q = new URLSearchParams();
  if (max > 0) q.set('max', String(max));
  if (pdm) q.set('pdm', pdm);
  if (pdm && version > 1) q.set('v', String(version));
  const qs = q.toString();
  return `/api/maps/${mapId}/layers/${name}.${format}${qs ? `?${qs}` : ''}`;
}

// A PNG as an ImageBitmap (fetched with the token, so it works behind --token).
export async function fetchImage(url, signal) {
  const blob = await (await request(url, { signal })).blob();
  return createImageBitmap(blob);
}

// Raw little-endian float32 raster: {rows, cols, cellW, cellH, data: Float32Array}; NaN = nodata.
export async function fetchF32(url, signal) {
  const response = await request(url, { signal });
  const rows = Number(response.headers.get('X-Rows'));
  const cols = Number(response.headers.get('X-Cols'));
  const buffer = await response.arrayBuffer();
  if (!(rows > 0 && cols > 0) || buffer.byteLength !== rows * cols * 4)
    throw new ApiError(0, 'bad_layer', `layer ${url}: size ${rows}×${cols} does not match ${buffer.byteLength} bytes`, '');
  // DataView keeps this right on a big-endian client too.
  let data;
  if (new Uint8Array(new Uint16Array([1]).buffer)[0] === 1) {
    data = new Float32Array(buffer);
  } else {
    const view = new DataView(buffer);
    data = new Float32Array(rows * cols);
    for (let i = 0; i < data.length; i++) data[i] = view.getFloat32(4 * i, true);
  }
  return {
    rows, cols, data,
    cellW: Number(response.headers.get('X-Cell-Width-M')) || 1,
    cellH: Number(response.headers.get('X-Cell-Height-M')) || 1,
  };
}

// Downloads a server file with the token (for export buttons behind --token).
export async function downloadWithToken(url, filename) {
  const blob = await (await request(url)).blob();
  const href = URL.createObjectURL(blob);
  const a = document.createElement('a');
  a.href = href;
  a.download = filename;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(href), 10000);
}

export function hasToken() {
  return Boolean(sessionToken);
}

// Multipart DEM upload with progress: each file is a part named "file"; `fields` are plain parts
// (name, cell, crop | crop_px, vertical_scale, body: the server's DEM import options), empty ones
// left out. Resolves to the new map.
export function uploadDem(files, fields = {}, onProgress = () => {}) {
  return new Promise((resolve, reject) => {
    const form = new FormData();
    for (const f of files) form.append('file', f, f.name);
    for (const [key, value] of Object.entries(fields))
      if (value !== '' && value !== null && value !== undefined) form.append(key, String(value));
    const xhr = new XMLHttpRequest();
    xhr.open('POST', '/api/maps');
    if (sessionToken) xhr.setRequestHeader('Authorization', `Bearer ${sessionToken}`);
    xhr.upload.onprogress = (e) => onProgress(e.lengthComputable ? e.loaded / e.total : NaN, e.loaded, 'upload');
    xhr.upload.onload = () => onProgress(1, 0, 'processing');
    xhr.onload = () => {
      let body = null;
      try { body = JSON.parse(xhr.responseText); } catch { /* not JSON */ }
      if (xhr.status >= 200 && xhr.status < 300 && body) return resolve(body);
      const e = body && body.error ? body.error : {};
      reject(new ApiError(xhr.status, e.code, e.message || `upload failed: HTTP ${xhr.status}`, e.field));
    };
    xhr.onerror = () => reject(new ApiError(0, 'network', 'the upload failed: the server closed the connection', 'file'));
    xhr.send(form);
  });
}

export function streamUrl(missionId) {
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const q = sessionToken ? `?token=${encodeURIComponent(sessionToken)}` : '';
  return `${proto}//${location.host}/api/missions/${missionId}/stream${q}`;
}

// WS /api/events for one map (issue 26), resuming after `since` when given.
export function eventsUrl(mapId, since) {
  const proto = location.protocol === 'https:' ? 'wss:' : 'ws:';
  const q = new URLSearchParams();
  if (mapId) q.set('map', mapId);
  if (Number.isInteger(since)) q.set('since', String(since));
  if (sessionToken) q.set('token', sessionToken);
  const qs = q.toString();
  return `${proto}//${location.host}/api/events${qs ? `?${qs}` : ''}`;
}
