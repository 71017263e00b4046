// Undo/redo of every edit on the map (issue 27): PDM components (add, drag, remove), zone corners
// and zones (Backspace drops the last corner, Escape asks before dropping a ring), rover placements
// and headings, the mission area — with Ctrl+Z, Ctrl+Shift+Z, Ctrl+Y and the toolbar buttons.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { mapPoint, openPage, suiteWithServer, waitForMap } from './lib/harness.mjs';

const app = (page, fn, arg) => page.evaluate(fn, arg);
const pdmComps = (page) => app(page, () => window.__roverplanApp.pdmEditor.comps.map((g) => [g.x, g.y]));
const zoneState = (page) => app(page, () => {
  const z = window.__roverplanApp.zoneEditor;
  return { zones: z.zones.map((q) => q.ring.length), drawing: z.drawing ? z.drawing.length : null, rings: z.zones.map((q) => q.ring) };
});

async function clickMap(page, x, y) {
  const p = await mapPoint(page, x, y);
  await page.mouse.click(p.x, p.y);
}

async function dragMap(page, [x0, y0], [x1, y1]) {
  const p = await mapPoint(page, x0, y0), q = await mapPoint(page, x1, y1);
  await page.mouse.move(p.x, p.y);
  await page.mouse.down();
  await page.mouse.move(q.x, q.y, { steps: 8 });
  await page.mouse.up();
}

suiteWithServer('undo and redo of map edits', { timeout: 180000 }, (ctx) => {
  let page, context, errors;

  test('the page opens with nothing to undo', async () => {
    ({ page, context, errors } = await openPage(ctx.browser, `${ctx.server.url}/`));
    await waitForMap(page);
    assert.equal(await page.isDisabled('#undo'), true);
    assert.equal(await page.isDisabled('#redo'), true);
  });

  test('PDM: add, drag and remove Gaussians, each undone and redone', async () => {
    await page.click('#tab-pdm');
    await clickMap(page, 40, 40);
    await clickMap(page, 100, 90);
    assert.equal((await pdmComps(page)).length, 2);
    await page.keyboard.press('Control+z');
    assert.equal((await pdmComps(page)).length, 1, 'Ctrl+Z removes the last Gaussian added');
    assert.equal(await page.isDisabled('#redo'), false);
    await page.keyboard.press('Control+Shift+z');
    assert.deepEqual((await pdmComps(page)).length, 2, 'Ctrl+Shift+Z adds it again');
    // A drag of the first centre: one step, whatever the number of moves.
    const [x0, y0] = (await pdmComps(page))[0];
    await dragMap(page, [x0, y0], [x0 + 20, y0 + 10]);
    const moved = (await pdmComps(page))[0];
    assert.ok(Math.abs(moved[0] - (x0 + 20)) < 1 && Math.abs(moved[1] - (y0 + 10)) < 1, `dragged to ${moved}`);
    await page.click('#undo');
    const back = (await pdmComps(page))[0];
    assert.ok(Math.abs(back[0] - x0) < 1e-9 && Math.abs(back[1] - y0) < 1e-9, `one undo brings the whole drag back: ${back}`);
    await page.keyboard.press('Control+y');
    assert.ok(Math.abs((await pdmComps(page))[0][0] - (x0 + 20)) < 1, 'Ctrl+Y redoes the drag');
    // Remove with the list's button, then undo.
    await page.click('#pdm-components [data-component="0"] button.remove');
    assert.equal((await pdmComps(page)).length, 1);
    await page.keyboard.press('Control+z');
    assert.equal((await pdmComps(page)).length, 2, 'the removed Gaussian is back');
    assert.match(await page.getAttribute('#redo', 'title'), /Redo remove Gaussian 1/, 'the buttons name the step');
  });

  test('zones: corners, Backspace, Escape asks, a closed zone and a moved corner undone', async () => {
    await page.click('#tab-maps');
    await page.click('#zones-draw');
    await clickMap(page, 20, 20);
    await clickMap(page, 60, 20);
    await clickMap(page, 60, 60);
    assert.equal((await zoneState(page)).drawing, 3);
    await page.keyboard.press('Backspace');
    assert.equal((await zoneState(page)).drawing, 2, 'Backspace drops the last corner');
    await page.keyboard.press('Control+z');
    assert.equal((await zoneState(page)).drawing, 3, 'and Ctrl+Z brings it back');
    // Escape asks: "cancel" keeps the ring, "OK" drops it; Ctrl+Z restores it.
    page.once('dialog', (d) => d.dismiss());
    await page.keyboard.press('Escape');
    assert.equal((await zoneState(page)).drawing, 3, 'dismissed: the ring is kept');
    let asked = '';
    page.once('dialog', (d) => { asked = d.message(); d.accept(); });
    await page.keyboard.press('Escape');
    assert.match(asked, /Discard the unfinished zone \(3 corners\)/);
    assert.equal((await zoneState(page)).drawing, null);
    await page.keyboard.press('Control+z');
    assert.equal((await zoneState(page)).drawing, 3, 'the discarded ring is back');
    await clickMap(page, 20, 60);
    await page.keyboard.press('Enter');
    let z = await zoneState(page);
    assert.deepEqual(z.zones, [4]);
    assert.equal(z.drawing, null);
    await page.keyboard.press('Control+z');
    z = await zoneState(page);
    assert.deepEqual(z.zones, [], 'undo of "close" reopens the ring');
    assert.equal(z.drawing, 4);
    await page.keyboard.press('Control+Shift+z');
    z = await zoneState(page);
    assert.deepEqual(z.zones, [4]);
    // Drag a corner, undo it.
    const before = z.rings[0][2];
    await dragMap(page, before, [before[0] + 15, before[1] + 15]);
    const after = (await zoneState(page)).rings[0][2];
    assert.ok(Math.abs(after[0] - before[0] - 15) < 1, `moved corner ${after}`);
    await page.keyboard.press('Control+z');
    assert.deepEqual((await zoneState(page)).rings[0][2], before, 'the corner is back where it was');
    // Delete the zone from its list and undo.
    await page.click('#zone-list [data-zone="0"] button[aria-label="delete zone 1"]');
    assert.deepEqual((await zoneState(page)).zones, []);
    await page.keyboard.press('Control+z');
    assert.deepEqual((await zoneState(page)).zones, [4]);
    await page.click('#zones-draw');
  });

  test('rovers: a placement with its heading drag is one step', async () => {
    await page.click('#tab-mission');
    await page.fill('#m-rover-count', '2');
    await page.dispatchEvent('#m-rover-count', 'input');
    assert.equal(await page.getAttribute('#m-place', 'aria-pressed'), 'true');
    await clickMap(page, 30, 40);
    await dragMap(page, [100, 100], [110, 110]);
    const rovers = await app(page, () => window.__roverplanApp.missionForm.rovers);
    assert.ok(Math.abs(rovers[1].heading - 45) <= 2, JSON.stringify(rovers));
    await page.keyboard.press('Control+z');
    let now = await app(page, () => window.__roverplanApp.missionForm.rovers);
    assert.equal(now[1], null, 'rover 2 unplaced');
    assert.ok(now[0] && Math.abs(now[0].x - 30) < 0.5);
    assert.equal(await page.inputValue('#m-rovers input[data-rover="1"][data-key="x"]'), '', 'the form follows');
    await page.keyboard.press('Control+Shift+z');
    now = await app(page, () => window.__roverplanApp.missionForm.rovers);
    assert.deepEqual(now[1], rovers[1], 'redo places it again, with its heading');
    // A heading typed into the list is a step too.
    await page.fill('#m-rovers input[data-rover="0"][data-key="heading"]', '90');
    await page.dispatchEvent('#m-rovers input[data-rover="0"][data-key="heading"]', 'change');
    assert.equal((await app(page, () => window.__roverplanApp.missionForm.rovers))[0].heading, 90);
    await page.click('#undo');
    assert.equal((await app(page, () => window.__roverplanApp.missionForm.rovers))[0].heading, rovers[0].heading);
  });

  test('the mission area: drawn and cleared, each undone', async () => {
    await page.click('#m-area-draw');
    await dragMap(page, [10, 10], [70, 50]);
    const drawn = await page.inputValue('#m-area');
    assert.match(drawn, /^10, 10, 70, 50$/);
    await page.click('#m-area-clear');
    assert.equal(await page.inputValue('#m-area'), '');
    await page.keyboard.press('Control+z');
    assert.equal(await page.inputValue('#m-area'), drawn, 'undo of "clear"');
    await page.keyboard.press('Control+z');
    assert.equal(await page.inputValue('#m-area'), '', 'undo of the drawing');
    await page.keyboard.press('Control+y');
    assert.equal(await page.inputValue('#m-area'), drawn);
    assert.deepEqual(await app(page, () => window.__roverplanApp.areaTool.outline), [10, 10, 70, 50], 'the outline follows');
  });

  test('the history is bounded and a new map starts it afresh', async () => {
    const limit = await app(page, async () => (await import('./js/undo_stack.js')).UNDO_LIMIT);
    assert.equal(limit, 200);
    const n = await app(page, (k) => {
      const { undoHistory } = window.__roverplanApp;
      const owner = { restore() {} };
      for (let i = 0; i < k; i++) undoHistory.push(owner, `step ${i}`, { i }, { i: i + 1 });
      return [undoHistory.done.length, undoHistory.done[0].label];
    }, limit + 20);
    assert.deepEqual(n, [limit, 'step 20'], 'the oldest steps are dropped');
    await app(page, () => window.__roverplanApp.state.emit('map', window.__roverplanApp.state.map));
    assert.equal(await page.isDisabled('#undo'), true, 'another map: nothing to undo');
    assert.deepEqual(errors, []);
    await context.close();
  });
});
