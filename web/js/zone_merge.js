// "Keep both" for keep-out zones (issue 26): a three-way merge of zone lists {id, version, ring,
// name} — base (what my edits started from), mine (the editor's) and theirs (saved since). Zones
// are a set, so both sides' work stays:
// - every zone of theirs stays, except one I deleted that they left as it was;
// - a zone I added (no id) is added;
// - a zone I changed that they left as it was becomes mine; one we both changed (or they
//   deleted) stays theirs and mine is added beside it, as a new zone.

const same = (a, b) => Boolean(a && b) && a.name === b.name && JSON.stringify(a.ring) === JSON.stringify(b.ring);

export function mergeZones(base, mine, theirs) {
  const byId = (list) => new Map(list.filter((z) => z.id).map((z) => [z.id, z]));
  const baseById = byId(base), mineById = byId(mine);
  const out = [];
  for (const t of theirs) {
    const b = baseById.get(t.id), m = mineById.get(t.id);
    const theyKept = same(t, b);
    if (b && !m && theyKept) continue;           // I deleted it, they did not touch it
    if (m && theyKept && !same(m, b)) out.push({ ...m, version: t.version });  // only I changed it
    else out.push(t);
  }
  const theirsById = byId(theirs);
  for (const m of mine) {
    if (!m.id) {
      out.push(m);  // new here
      continue;
    }
    const b = baseById.get(m.id), t = theirsById.get(m.id);
    if (same(m, b)) continue;              // not changed here: theirs decided above
    if (t && (same(t, b) || same(t, m))) continue;  // mine replaced theirs above, or the same change
    out.push({ ring: m.ring, name: m.name });  // both changed it, or they deleted it: mine as a new zone
  }
  return out;
}
