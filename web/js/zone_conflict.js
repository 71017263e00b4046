// A zone save answered 412 (issue 26): another operator saved this map's zones after the edits
// started. Nothing was overwritten; both sets are shown (conflict_view.js) and the operator keeps
// mine (saved over theirs, naming their version), takes theirs, or keeps both (zone_merge.js).

import { api } from './api.js';
import { drawRings } from './conflict_view.js';
import { state } from './state.js';
import { $, fmt } from './util.js';
import { mergeZones } from './zone_merge.js';
import { area, zonesFromGeoJson, zonesToGeoJson } from './zone_geometry.js';

const plural = (n) => `${n} zone${n === 1 ? '' : 's'}`;

export async function showZoneConflict(editor, map, current, mine) {
  const theirs = zonesFromGeoJson(current);
  const base = zonesFromGeoJson(editor.baseZones || { features: [] });
  // Who saved theirs: the newest entry of the set's history.
  const by = await api.history(map.id, 'zones').then((h) => (h[0]?.version === current.version ? h[0].by : ''), () => '');
  state.zones = current;
  state.emit('zones', state.zones);
  editor.changed();
  const lines = (list) => list.map((z, i) => `${z.name || (z.id ? `zone ${z.id}` : `new zone ${i + 1}`)} · ${z.ring.length} points · ${fmt(area(z.ring))} m²`);
  const resave = async (zones) => {
    if (state.map?.id !== map.id) throw new Error('another map is shown now: open this one again to save');
    editor.zones = zones;
    editor.baseVersion = current.version;
    editor.saved(await api.saveZones(map.id, zonesToGeoJson(zones), 'local', current.version));
    editor.keepDraft();
  };
  editor.conflicts.show({
    title: 'zones not saved: both versions shown', what: "this map's keep-out zones", version: current.version, by,
    mine: { summary: plural(mine.length), lines: lines(mine), draw: (ctx, v, c) => drawRings(ctx, v, mine.map((z) => z.ring), c, [7, 4]) },
    theirs: { summary: plural(theirs.length), lines: lines(theirs), draw: (ctx, v, c) => drawRings(ctx, v, theirs.map((z) => z.ring), c) },
    keepMine: async () => {
      await resave(mine.map((z) => ({ ...z })));
      $('zones-status').textContent = `saved ${plural(editor.zones.length)} (yours, over v${current.version})`;
    },
    takeTheirs: async () => {
      editor.saved(current);
      editor.keepDraft();
      $('zones-status').textContent = `theirs loaded (${plural(editor.zones.length)})`;
    },
    keepBoth: async () => {
      await resave(mergeZones(base, mine, theirs));
      $('zones-status').textContent = `saved ${plural(editor.zones.length)} (both kept)`;
    },
  });
}
