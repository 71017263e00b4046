// A conflict shown, not hidden (issue 26): when a save is answered 412 (someone saved the same
// object since this page read it), both versions are shown side by side in a panel over the map
// and both are drawn on the map (yours in orange, theirs in cyan), and the operator chooses: keep
// mine (saved again over theirs, naming their version), take theirs (my edits dropped), or keep
// both (merged: zones and PDM components are sets, so both sides' additions and changes stay).
// Nothing is saved until one is chosen; the edits stay in the draft meanwhile ("decide later"
// closes the panel and keeps them; saving again shows the conflict again).

import { state } from './state.js';
import { $, el, showError } from './util.js';

export const MINE = '#ffb347';
export const THEIRS = '#3ad6ff';

export class ConflictView {
  constructor({ view }) {
    this.view = view;
    this.current = null;
    view.addLayer({ id: 'conflict', order: 60, draw: (ctx, v) => this.draw(ctx, v) });
    state.on('map', () => this.close());  // the edits stay in their map's draft
  }

  // c: {title, what, mine: {summary, lines[], draw(ctx, v, colour)}, theirs: {...}, by, version,
  //     keepMine(), takeTheirs(), keepBoth()} (the actions are async; the panel closes after one).
  show(c) {
    this.current = c;
    const side = (who, part, colour) => el('div', { class: 'conflict-side', dataset: { side: who } },
      el('h3', {}, el('span', { class: 'swatch', style: `background:${colour}` }), who === 'mine' ? 'yours (not saved)' : `theirs (v${c.version}${c.by ? `, ${c.by}` : ''})`),
      el('div', { class: 'summary' }, part.summary),
      el('ul', {}, ...part.lines.map((l) => el('li', {}, l))));
    const act = (label, fn, title) => el('button', { title, onclick: () => this.run(fn) }, label);
    const node = $('conflict');
    node.replaceChildren(
      el('div', { class: 'float-title' }, `⚠ ${c.title}`),
      el('p', { class: 'help' }, `${c.by || 'Another operator'} saved ${c.what} after you loaded it. Nothing was overwritten: choose what to keep.`),
      el('div', { class: 'conflict-sides' }, side('mine', c.mine, MINE), side('theirs', c.theirs, THEIRS)),
      el('div', { class: 'form-row' },
        act('keep mine', c.keepMine, 'save yours over theirs'),
        act('take theirs', c.takeTheirs, 'drop your edits and load theirs'),
        act('keep both', c.keepBoth, 'merge: theirs plus your additions and changes, then save'),
        el('button', { class: 'later', title: 'close: your edits stay unsaved (a draft); saving again shows this again', onclick: () => this.close() }, 'decide later')),
      el('div', { id: 'conflict-error', class: 'error', role: 'alert', hidden: true }));
    node.hidden = false;
    // Both versions in sight: the map is fitted below the panel.
    this.view.padTop = node.offsetHeight + 8;
    this.view.fit();
    this.view.invalidate();
  }

  async run(fn) {
    const node = $('conflict');
    for (const b of node.querySelectorAll('button')) b.disabled = true;
    try {
      await fn();
      this.close();
    } catch (err) {
      showError($('conflict-error'), err);
      for (const b of node.querySelectorAll('button')) b.disabled = false;
    }
  }

  get open() {
    return Boolean(this.current);
  }

  close() {
    this.current = null;
    $('conflict').hidden = true;
    $('conflict').replaceChildren();
    this.view.padTop = 0;
    this.view.invalidate();
  }

  draw(ctx, v) {
    const c = this.current;
    if (!c) return;
    ctx.save();
    c.theirs.draw?.(ctx, v, THEIRS);
    c.mine.draw?.(ctx, v, MINE);
    ctx.restore();
  }
}

// Outlines of polygons (open rings, local frame) in one colour: a conflict's or a version's zones.
export function drawRings(ctx, v, rings, colour, dash = []) {
  ctx.strokeStyle = colour;
  ctx.lineWidth = 2.5;
  ctx.setLineDash(dash);
  for (const ring of rings) {
    ctx.beginPath();
    ring.forEach(([x, y], i) => {
      const [sx, sy] = v.worldToScreen(x, y);
      if (i === 0) ctx.moveTo(sx, sy);
      else ctx.lineTo(sx, sy);
    });
    ctx.closePath();
    ctx.stroke();
  }
  ctx.setLineDash([]);
}

// Gaussians as their 1σ ellipses in one colour: a conflict's or a version's PDM components.
export function drawEllipses(ctx, v, comps, colour, dash = []) {
  ctx.strokeStyle = colour;
  ctx.lineWidth = 2;
  ctx.setLineDash(dash);
  for (const g of comps) {
    const [cx, cy] = v.worldToScreen(g.x, g.y);
    ctx.beginPath();
    ctx.ellipse(cx, cy, g.sigma_x * v.scale, g.sigma_y * v.scale, (-g.rotation_deg * Math.PI) / 180, 0, 2 * Math.PI);
    ctx.stroke();
  }
  ctx.setLineDash([]);
}
