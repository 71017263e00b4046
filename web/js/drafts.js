// Drafts (issue 26): unsaved edits kept in this browser per map and kind ("pdm", "zones",
// "mission"), so they survive switching maps and reloading the page until saved or discarded.
// Bounded by the browser's localStorage quota (about 5 MB per origin; a PDM of 256 components is
// about 30 KB): a draft that does not fit is not kept, and the page says so once.

const PREFIX = 'roverplan.draft.';
let warned = false;

const key = (mapId, kind) => `${PREFIX}${mapId}.${kind}`;

export function loadDraft(mapId, kind) {
  if (!mapId) return null;
  try {
    const text = localStorage.getItem(key(mapId, kind));
    return text ? JSON.parse(text) : null;
  } catch {
    return null;
  }
}

export function saveDraft(mapId, kind, value) {
  if (!mapId) return;
  try {
    localStorage.setItem(key(mapId, kind), JSON.stringify({ ...value, saved_at: new Date().toISOString() }));
  } catch (err) {
    if (!warned) console.warn(`draft not kept (${err.name}): the browser's storage is full or disabled`);
    warned = true;
  }
}

export function clearDraft(mapId, kind) {
  if (!mapId) return;
  try { localStorage.removeItem(key(mapId, kind)); } catch { /* storage disabled */ }
}

// Every draft of a map (it was deleted).
export function clearDrafts(mapId) {
  for (const kind of ['pdm', 'zones', 'mission']) clearDraft(mapId, kind);
}
