// Versions of a PDM in the editor (issue 26): a 412 on "update" shown with both versions
// (conflict_view.js) and resolved by keep mine / take theirs / keep both (components are a set:
// theirs plus mine that are neither theirs nor unchanged from the base), a change saved elsewhere
// followed, and the random draft's components.

import { api } from './api.js';
import { drawEllipses } from './conflict_view.js';
import { state } from './state.js';
import { $ } from './util.js';

// G random Gaussians over the map, as the server's `random` draws them (core/pdm randomGaussians:
// centres uniform, σ 5–20 % of the shorter side, any rotation) from a small seeded generator
// (mulberry32): the same seed gives the same draft here, not the server's numbers.
export function randomComponents(map, count, seed) {
  let a = (seed >>> 0) + 0x9e3779b9;
  const rnd = () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
  const side = Math.min(map.width_m, map.height_m);
  return Array.from({ length: count }, () => ({
    x: rnd() * map.width_m, y: rnd() * map.height_m,
    sigma_x: side * (0.05 + 0.15 * rnd()), sigma_y: side * (0.05 + 0.15 * rnd()),
    rotation_deg: Math.round(rnd() * 1800) / 10, weight: 1,
  }));
}

const same = (a, b) => ['x', 'y', 'sigma_x', 'sigma_y', 'rotation_deg', 'weight'].every((k) => Math.abs(a[k] - b[k]) < 1e-9);

export async function showPdmConflict(editor, map, current) {
  const b = editor.base, mine = editor.comps.map((g) => ({ ...g }));
  const theirs = (current.components || []).map((g) => ({ ...g }));
  const by = await api.history(map.id, `pdms/${b.id}`).then((h) => (h[0]?.version === current.version ? h[0].by : ''), () => '');
  const line = (g, i) => `${i + 1}: (${g.x.toFixed(1)}, ${g.y.toFixed(1)}) σ ${g.sigma_x.toFixed(1)}×${g.sigma_y.toFixed(1)} m, w ${g.weight}`;
  const put = async (comps, name) => editor.updated(await api.changePdm(map.id, b.id, { name, components: comps }, current.version));
  editor.conflicts.show({
    title: `PDM “${b.name}” not saved: both versions shown`, what: `the PDM “${current.name}”`, version: current.version, by,
    mine: { summary: `${mine.length} components`, lines: mine.map(line), draw: (ctx, v, c) => drawEllipses(ctx, v, mine, c, [6, 4]) },
    theirs: { summary: `${theirs.length} components`, lines: theirs.map(line), draw: (ctx, v, c) => drawEllipses(ctx, v, theirs, c) },
    keepMine: () => put(mine, $('pdm-name').value.trim() || current.name),
    takeTheirs: async () => {
      editor.dirty = false;
      editor.updated(current);
    },
    // Components are a set: theirs, plus mine that are neither theirs nor unchanged from the base.
    keepBoth: () => put([...theirs, ...mine.filter((g) => !theirs.some((t) => same(t, g)) && !b.comps.some((o) => same(o, g)))], current.name),
  });
}

// A PDM of this map changed elsewhere (an event; null after a resync): the list is read again;
// the one loaded here follows when it has no unsaved edits, else they are kept (update shows both).
export async function followRemotePdm(editor, e) {
  await editor.refresh();
  const b = editor.base;
  if (!b || (e && e.id !== b.id)) return;
  const now = state.pdms.find((p) => p.id === b.id);
  if (!now) {
    $('pdm-save-status').textContent = `“${b.name}” was deleted${e?.by ? ` by ${e.by}` : ''}; your components are kept as a draft`;
    editor.base = null;
    editor.dirty = editor.comps.length > 0;
    if (state.pdmId === b.id) {
      state.pdmId = '';
      state.emit('pdm-selected', '');
    }
    editor.changed();
    return;
  }
  if ((now.version ?? 1) === b.version) return;
  if (!editor.dirty) {
    editor.updated(now);
    $('pdm-save-status').textContent = `“${now.name}” changed${e?.by ? ` by ${e.by}` : ''} (v${now.version})`;
  } else {
    $('pdm-save-status').textContent = `“${now.name}” changed${e?.by ? ` by ${e.by}` : ''} (v${now.version}); your edits are kept — update shows both`;
  }
}
