// Presence (issue 26): the operator's name (typed once, kept in this browser: api.js) and who else
// has this map open and what they are editing, shown next to the map title. What this page edits
// is said in the hello ("zones", "pdm:<id>", "pdm:new", "mission", or ''); others' editing is also
// marked on the object (editorsOf, read by the PDM and zone lists).

import { getOperator, setOperator } from './api.js';
import { state } from './state.js';
import { $, el } from './util.js';

const WHAT = { zones: 'keep-out zones', 'pdm:new': 'a new PDM', mission: 'a mission' };

export class Presence {
  constructor(feed) {
    this.feed = feed;
    this.others = new Map();  // connection id -> {name, editing}
    this.editing = '';
    const input = $('operator');
    input.value = getOperator();
    input.addEventListener('change', () => {
      input.value = setOperator(input.value);
      this.say();
    });
  }

  // What this page now edits ('' for nothing); said to the others when it changes.
  setEditing(what) {
    if (what === this.editing) return;
    this.editing = what;
    this.say();
  }

  say() {
    this.feed.say({ name: getOperator() || 'anonymous', map: state.map?.id || '', editing: this.editing });
  }

  ready(msg) {
    this.others.clear();
    for (const p of msg.presence || []) if (p.id !== this.feed.connection) this.others.set(p.id, { name: p.name, editing: p.editing });
    this.render();
  }

  event(e) {
    if (e.id === this.feed.connection) return;
    if (e.kind === 'left' || (e.map && e.map !== state.map?.id)) this.others.delete(e.id);
    else this.others.set(e.id, { name: e.extra?.name || e.by || 'someone', editing: e.extra?.editing || '' });
    this.render();
  }

  // The names of the others editing `what` (e.g. "zones", "pdm:p12").
  editorsOf(what) {
    return [...this.others.values()].filter((p) => p.editing === what).map((p) => p.name);
  }

  describe(editing) {
    if (!editing) return '';
    if (WHAT[editing]) return WHAT[editing];
    if (editing.startsWith('pdm:')) {
      const p = state.pdms.find((q) => q.id === editing.slice(4));
      return p ? `PDM “${p.name}”` : 'a PDM';
    }
    return editing;
  }

  render() {
    const node = $('presence');
    const list = [...this.others.values()];
    node.hidden = list.length === 0;
    node.replaceChildren(...list.map((p) => el('span', { class: 'who', title: p.editing ? `${p.name} is editing ${this.describe(p.editing)}` : `${p.name} has this map open` },
      el('span', { class: 'dot' }), p.name, p.editing ? el('span', { class: 'muted' }, ` · ${this.describe(p.editing)}`) : '')));
    if (list.length) node.prepend(el('span', { class: 'muted' }, 'also here:'));
    state.emit('presence', list);
  }
}
