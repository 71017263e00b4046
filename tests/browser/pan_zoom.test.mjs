// Pan and zoom on the 2D map are OpenLayers' own interactions (issue 24): a drag pans (the ground
// under the press follows the pointer), the wheel zooms about the pointer, a double click zooms in
// the pan tool, the arrow keys pan, the view stops at the tile grid's limits; in the zones tool a
// drag pans and adds no corner while a click adds one; two quick clicks placing rovers are no
// double-click zoom.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { mapPoint, openPage, sleep, suiteWithServer, waitForMap } from './lib/harness.mjs';

const viewOf = (page) => page.evaluate(() => {
  const v = window.__roverplanApp.view;
  return { cx: v.cx, cy: v.cy, scale: v.scale };
});

// The view once OL has no animation running (wheel zoom, double-click zoom, inertia).
async function settled(page) {
  await page.waitForFunction(() => !window.__roverplanApp.view.olView.getAnimating() && !window.__roverplanApp.view.olView.getInteracting());
  return viewOf(page);
}

// A drag from a to b: a 2-px start, then 12 steps (OL's DragPan pans from its first drag event,
// past the 1-px move tolerance: the start is not panned), held still before the release so
// DragPan's inertia does not carry the view on (a gesture, not a wait).
async function drag(page, a, b) {
  await page.mouse.move(a.x, a.y);
  await page.mouse.down();
  await page.mouse.move(a.x + 2, a.y);
  await page.mouse.move(b.x, b.y, { steps: 12 });
  await sleep(200);
  await page.mouse.up();
}

// The local point (metres) under page point (x, y).
const worldAt = (page, x, y) => page.evaluate(([x, y]) => {
  const v = window.__roverplanApp.view, r = v.canvas.getBoundingClientRect();
  return v.screenToWorld(x - r.left, y - r.top);
}, [x, y]);

suiteWithServer('pan and zoom', { timeout: 180000 }, (ctx) => {
  test('a drag pans, the wheel zooms about the pointer, a double click zooms, the arrows pan, the zoom has limits', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    const map = await page.evaluate(() => window.__roverplanApp.state.map);

    // A drag: the ground under the press ends under the release, but for the 2-px start.
    const a = await mapPoint(page, 75, 75), b = { x: a.x - 120, y: a.y + 70 };
    const v0 = await viewOf(page);
    await drag(page, a, b);
    const v1 = await settled(page);
    assert.equal(v1.scale, v0.scale, 'a drag does not zoom');
    const [gx, gy] = await worldAt(page, b.x - 2, b.y);
    const px = 1 / v1.scale;
    assert.ok(Math.abs(gx - 75) <= 1.5 * px && Math.abs(gy - 75) <= 1.5 * px, `the pressed ground (75, 75) is 2 px left of the release: (${gx}, ${gy})`);

    // The wheel: zoomed in, the ground under the pointer stays there.
    const p = { x: b.x + 40, y: b.y - 30 };
    const under = await worldAt(page, p.x, p.y);
    await page.mouse.move(p.x, p.y);
    await page.mouse.wheel(0, -120);
    await page.waitForFunction((s) => window.__roverplanApp.view.scale > s * 1.1, v1.scale);
    const v2 = await settled(page);
    const after = await worldAt(page, p.x, p.y);
    console.log(`# wheel: ${v1.scale.toFixed(3)} → ${v2.scale.toFixed(3)} px/m`);
    assert.ok(Math.hypot(after[0] - under[0], after[1] - under[1]) <= 1.5 / v2.scale, `the ground under the pointer stays: ${under} → ${after}`);

    // A double click in the pan tool: twice the scale.
    await page.mouse.dblclick(p.x, p.y);
    await page.waitForFunction((s) => window.__roverplanApp.view.scale > s * 1.5, v2.scale);
    const v3 = await settled(page);
    assert.ok(Math.abs(v3.scale / v2.scale - 2) < 0.01, `a double click doubles the scale: ${v2.scale} → ${v3.scale}`);

    // The arrow keys on the focused map pan it (OL's KeyboardPan: 128 px a press).
    await page.focus('#map-canvas');
    await page.keyboard.press('ArrowRight');
    await page.waitForFunction((x) => window.__roverplanApp.view.cx > x, v3.cx);
    const v4 = await settled(page);
    assert.ok(Math.abs((v4.cx - v3.cx) * v4.scale - 128) < 1 && v4.cy === v3.cy, `ArrowRight: ${(v4.cx - v3.cx) * v4.scale} px east`);

    // The limits: in to 32 px a cell (three zooms past the tile grid's finest), out to a quarter of
    // the scale of the grid's coarsest zoom (the whole map in one tile).
    await page.focus('#map-canvas');
    for (let i = 0; i < 20; i++) await page.keyboard.press('+');
    const finest = (await viewOf(page)).scale;
    for (let i = 0; i < 30; i++) await page.keyboard.press('-');
    const coarsest = (await viewOf(page)).scale;
    console.log(`# zoom limits: ${coarsest.toFixed(4)} … ${finest.toFixed(2)} px/m (a cell ${(finest * map.cell_size_m).toFixed(2)} px at the closest)`);
    assert.ok(Math.abs(finest * map.cell_size_m - 32) < 1e-6, `closest: a cell is 32 px (${finest * map.cell_size_m})`);
    assert.ok(Math.abs(coarsest * map.tiles.resolutions[0] * 4 - 1) < 1e-6, `farthest: ${coarsest} px/m`);
    await page.keyboard.press('0');  // fits the map again
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('in the zones tool a drag pans and a click adds a corner; quick clicks placing rovers do not zoom', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.click('#zones-draw');
    const a = await mapPoint(page, 40, 40);
    const v0 = await viewOf(page);
    await drag(page, a, { x: a.x + 82, y: a.y - 40 });
    const v1 = await settled(page);
    assert.ok(Math.abs(v1.cx - (v0.cx - 80 / v0.scale)) <= 1.5 / v0.scale && Math.abs(v1.cy - (v0.cy - 40 / v0.scale)) <= 1.5 / v0.scale,
      `the drag panned by (80, −40) px: (${v0.cx}, ${v0.cy}) → (${v1.cx}, ${v1.cy})`);
    assert.equal(await page.evaluate(() => window.__roverplanApp.zoneEditor.drawing), null, 'the drag drew no corner');
    const c = await mapPoint(page, 50, 50);
    await page.mouse.click(c.x, c.y);
    const drawing = await page.evaluate(() => window.__roverplanApp.zoneEditor.drawing);
    assert.equal(drawing.length, 1, 'a click adds a corner');
    assert.ok(Math.hypot(drawing[0][0] - 50, drawing[0][1] - 50) <= 1.5 / v1.scale, `at the click: ${drawing[0]}`);
    await page.keyboard.press('Escape');
    await page.click('#zones-draw');

    // The Mission tab places rovers on clicks: two quick clicks (the second ends the placing,
    // back to the pan tool) place two rovers and leave the view as it was.
    await page.click('#tab-mission');
    await page.fill('#m-rover-count', '2');
    const r1 = await mapPoint(page, 30, 30), r2 = await mapPoint(page, 60, 30);
    const v2 = await viewOf(page);
    await page.mouse.click(r1.x, r1.y);
    await page.mouse.click(r2.x, r2.y);
    const rovers = await page.evaluate(() => window.__roverplanApp.missionForm.rovers);
    assert.ok(rovers.every(Boolean), `both placed: ${JSON.stringify(rovers)}`);
    // OL's double click comes with the second release: a zoom would be animating now.
    assert.equal(await page.evaluate(() => window.__roverplanApp.view.olView.getAnimating()), false, 'no double-click zoom');
    assert.deepEqual(await viewOf(page), v2, 'the view as it was');
    assert.deepEqual(errors, []);
    await context.close();
  });
});
