// The mission form's values as a draft of the map (issue 26, drafts.js): planner, its parameter
// fields as typed (even half-typed), PDM choice, rovers placed, area, name and pace come back
// when the map is shown again or the page is reloaded. "Duplicate and edit" (MissionForm.load)
// fills the form itself: no draft is restored over it.

import { loadDraft, saveDraft } from './drafts.js';
import { state } from './state.js';
import { $ } from './util.js';

// Fields taken from the map rather than typed, or not values at all.
const SKIP = new Set(['m-planner', 'm-pdm', 'm-keep-out', 'm-file', 'm-rover-count', 'm-preset']);

export class FormDraft {
  constructor(form) {
    this.form = form;
    this.quiet = 0;  // >0 while the form is filled by code (a restore, a mission file)
    // The map whose values the form holds: none between a map switch and its draft's restore
    // (the form resets itself for the new map meanwhile, which must not overwrite that draft).
    this.mapId = null;
    const load = form.load.bind(form);
    form.load = async (...args) => {
      this.quiet++;
      try {
        return await load(...args);
      } finally {
        this.quiet--;
        this.mapId = state.map?.id || null;
        this.capture();
      }
    };
    const renderRovers = form.renderRovers.bind(form);
    form.renderRovers = () => {
      renderRovers();
      this.capture();
    };
    for (const type of ['input', 'change']) $('mission-form').addEventListener(type, () => this.capture());
    this.restoring = null;
    state.on('map', (map) => {
      this.mapId = null;
      if (map && !this.quiet) this.restoring = this.restore(map);
    });
  }

  capture() {
    const map = state.map;
    if (!map || this.quiet || map.id !== this.mapId || !this.form.planner) return;
    const fields = {};
    for (const input of $('mission-form').querySelectorAll('input[id], select[id], textarea[id]')) {
      if (SKIP.has(input.id) || input.type === 'file' || input.closest('#m-rovers')) continue;
      fields[input.id] = input.type === 'checkbox' ? input.checked : input.value;
    }
    saveDraft(map.id, 'mission', {
      planner: $('m-planner').value, fields, pdm: this.form.pdmChosen ? $('m-pdm').value : null, rovers: this.form.rovers,
    });
  }

  async restore(map) {
    const d = loadDraft(map.id, 'mission');
    this.quiet++;
    try {
      await this.form.defaultsLoading;
      if (state.map !== map || this.quiet > 1) return;  // another map, or a mission file being loaded
      this.mapId = map.id;
      if (!d) return;
      const sel = $('m-planner');
      if ([...sel.options].some((o) => o.value === d.planner)) {
        sel.value = d.planner;
        this.form.renderParams();
      }
      for (const [id, value] of Object.entries(d.fields || {})) {
        const input = $(id);
        if (!input || SKIP.has(id)) continue;
        if (input.type === 'checkbox') input.checked = Boolean(value);
        else input.value = String(value);
      }
      this.form.updateDependent?.();
      if (d.pdm !== null && d.pdm !== undefined && [...$('m-pdm').options].some((o) => o.value === d.pdm)) {
        $('m-pdm').value = d.pdm;
        $('m-pdm').dispatchEvent(new Event('change'));
      }
      const rovers = Array.isArray(d.rovers) ? d.rovers.map((r) => (r && Number.isFinite(r.x) && Number.isFinite(r.y) ? { x: r.x, y: r.y, heading: r.heading ?? 0 } : null)) : [];
      if (rovers.length) {
        $('m-rover-count').value = String(rovers.length);
        this.form.rovers = rovers;
        const free = rovers.findIndex((r) => r === null);
        this.form.next = free < 0 ? 0 : free;
        this.form.renderRovers();
      }
      $('m-area').dispatchEvent(new Event('input'));
      this.form.view.invalidate();
    } finally {
      this.quiet--;
    }
  }
}
