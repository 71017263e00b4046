// One command history for every edit on the map (issue 27): PDM components and brush strokes, zone
// corners and zones, rover placements and headings, the mission area. Each editor owns its state
// and offers snapshot() / restore(snapshot); a command is {owner, label, before, after}: undo
// restores `before`, redo restores `after`. Snapshots (mementos) rather than inverse operations so
// an edit made of many pointer moves (a drag, a brush stroke) is one step and no editor has to
// write an inverse for each of its edits.
//
// Bounded: the oldest steps are dropped past LIMIT (snapshots are small: a PDM is at most a few
// hundred components, zones a few thousand corners; 200 steps stay well under a few MB).
// A new map clears the history (its edits belonged to the last map).

import { state } from './state.js';
import { $ } from './util.js';

export const UNDO_LIMIT = 200;

const clone = (v) => (v === undefined ? undefined : JSON.parse(JSON.stringify(v)));

class UndoStack {
  constructor() {
    this.done = [];
    this.undone = [];
    this.listeners = [];
  }

  // Records an edit that already happened. Equal before/after (a click that moved nothing) is no step.
  push(owner, label, before, after) {
    const b = clone(before), a = clone(after);  // the editor keeps changing its own arrays
    if (JSON.stringify(b) === JSON.stringify(a)) return false;
    this.done.push({ owner, label, before: b, after: a });
    if (this.done.length > UNDO_LIMIT) this.done.splice(0, this.done.length - UNDO_LIMIT);
    this.undone = [];
    this.changed();
    return true;
  }

  // Runs fn() between two snapshots of owner and records the difference as one step.
  record(owner, label, fn) {
    const before = clone(owner.snapshot());  // a copy: fn() may change the arrays in place
    const out = fn();
    this.push(owner, label, before, owner.snapshot());
    return out;
  }

  undo() {
    const c = this.done.pop();
    if (!c) return null;
    c.owner.restore(clone(c.before));
    this.undone.push(c);
    this.changed();
    return c.label;
  }

  redo() {
    const c = this.undone.pop();
    if (!c) return null;
    c.owner.restore(clone(c.after));
    this.done.push(c);
    this.changed();
    return c.label;
  }

  clear() {
    this.done = [];
    this.undone = [];
    this.changed();
  }

  onChange(fn) {
    this.listeners.push(fn);
  }

  changed() {
    for (const fn of this.listeners) fn(this);
  }
}

export const history = new UndoStack();

function isTextField(t) {
  return t && (t.tagName === 'INPUT' || t.tagName === 'TEXTAREA' || t.tagName === 'SELECT' || t.isContentEditable) &&
    !(t.tagName === 'INPUT' && ['button', 'checkbox', 'radio', 'range', 'file'].includes(t.type));
}

// The toolbar's Undo/Redo buttons and the keys: Ctrl+Z, Ctrl+Shift+Z, Ctrl+Y (⌘ on a Mac). In a
// text field the browser's own undo of the typing applies.
export function bindUndoControls() {
  const undo = $('undo'), redo = $('redo');
  const render = () => {
    const last = history.done[history.done.length - 1], next = history.undone[history.undone.length - 1];
    undo.disabled = !last;
    redo.disabled = !next;
    undo.title = last ? `Undo ${last.label} (Ctrl+Z)` : 'Nothing to undo (Ctrl+Z)';
    redo.title = next ? `Redo ${next.label} (Ctrl+Shift+Z or Ctrl+Y)` : 'Nothing to redo (Ctrl+Shift+Z or Ctrl+Y)';
  };
  undo.addEventListener('click', () => history.undo());
  redo.addEventListener('click', () => history.redo());
  history.onChange(render);
  render();
  window.addEventListener('keydown', (e) => {
    if (!(e.ctrlKey || e.metaKey) || e.altKey || isTextField(e.target)) return;
    const k = e.key.toLowerCase();
    if (k === 'z' && !e.shiftKey) history.undo();
    else if ((k === 'z' && e.shiftKey) || k === 'y') history.redo();
    else return;
    e.preventDefault();
  });
  state.on('map', () => history.clear());
}
