// "Duplicate and edit" reopens exactly what a run used (issue 26): a mission records the versions
// of its PDM and of the map's zone set (spec.used); when either has been saved again since, the
// version the run used is read from the history and put in its editor as unsaved edits (a draft
// on the current version: "update" / "save zones" make it the newest, a 412 if someone saves
// meanwhile). Returns what was reopened, for the status line ('' when the current versions are
// the ones used).

import { api } from './api.js';
import { state } from './state.js';

export async function reopenUsed(file, { pdmEditor, zoneEditor }) {
  const used = file.used || {}, map = state.map, said = [];
  if (!map || map.id !== file.map) return '';
  const pdm = file.pdm ? state.pdms.find((p) => p.id === file.pdm) : null;
  if (pdm && Number.isInteger(used.pdm_version) && used.pdm_version !== pdm.version) {
    try {
      const h = await api.historyVersion(map.id, `pdms/${pdm.id}`, used.pdm_version);
      pdmEditor.loadVersion(pdm, h.body?.meta?.components || [], used.pdm_version);
      said.push(`PDM “${pdm.name}” v${used.pdm_version} (now v${pdm.version}) in the PDM tab`);
    } catch (err) {
      said.push(`PDM “${pdm.name}” v${used.pdm_version} is no longer kept (${err.message}): v${pdm.version} is used`);
    }
  }
  const zonesNow = state.zones?.version ?? 0;
  if (Number.isInteger(used.zones_version) && used.zones_version > 0 && used.zones_version !== zonesNow) {
    try {
      const h = await api.historyVersion(map.id, 'zones', used.zones_version);
      zoneEditor.loadVersion(h.body, used.zones_version);
      said.push(`zones v${used.zones_version} (now v${zonesNow}) in the Maps tab`);
    } catch (err) {
      said.push(`zones v${used.zones_version} are no longer kept (${err.message})`);
    }
  }
  return said.length ? `this run used ${said.join('; ')}: unsaved until you save them` : '';
}
