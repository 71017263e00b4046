// The PDM brush (issue 27): in paint mode a drag lays Gaussians of the brush's σ and weight along
// the stroke, one every σ, without panning the map; Shift + drag erases the components under the
// brush; a stroke is one undo step. The mission form offers the map's latest PDM by default and
// warns when a searching planner has none.
import assert from 'node:assert/strict';
import { mkdirSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { test } from 'node:test';
import { mapPoint, openPage, postJson, repoRoot, suiteWithServer, waitForMap } from './lib/harness.mjs';

const shotsDir = resolve(repoRoot, '../shots');
const comps = (page) => page.evaluate(() => window.__roverplanApp.pdmEditor.comps.map((g) => ({ ...g })));
const viewState = (page) => page.evaluate(() => {
  const v = window.__roverplanApp.view;
  return { cx: v.cx, cy: v.cy, scale: v.scale, olCentre: v.olView.getCenter() };
});

async function stroke(page, [x0, y0], [x1, y1], steps = 40) {
  const p = await mapPoint(page, x0, y0), q = await mapPoint(page, x1, y1);
  await page.mouse.move(p.x, p.y);
  await page.mouse.down();
  await page.mouse.move(q.x, q.y, { steps });
  await page.mouse.up();
}

suiteWithServer('PDM brush', { timeout: 180000 }, (ctx) => {
  let page, context, errors;

  test('a drag paints Gaussians along the stroke and the map does not move', async () => {
    ({ page, context, errors } = await openPage(ctx.browser, `${ctx.server.url}/`));
    await waitForMap(page);
    await page.click('#tab-pdm');
    await page.click('#pdm-mode-paint');
    assert.equal(await page.isVisible('#pdm-brush'), true);
    await page.fill('#pdm-brush-sigma', '5');
    await page.fill('#pdm-brush-weight', '2');
    const before = await viewState(page);
    await stroke(page, [20, 75], [120, 75]);
    const after = await viewState(page);
    assert.deepEqual(after, before, 'painting never pans');
    const g = await comps(page);
    console.log(`# stroke 100 m with σ 5 m: ${g.length} Gaussians`);
    assert.ok(g.length >= 20 && g.length <= 22, `one every σ along 100 m: ${g.length}`);
    const px = 1 / after.scale;  // a mouse position is rounded to a CSS pixel
    for (const c of g) {
      assert.ok(Math.abs(c.y - 75) <= 2 * px, `on the stroke: y ${c.y}`);
      assert.equal(c.sigma_x, 5);
      assert.equal(c.sigma_y, 5);
      assert.equal(c.weight, 2);
    }
    const xs = g.map((c) => c.x).sort((a, b) => a - b);
    assert.ok(Math.abs(xs[0] - 20) <= 2 * px && xs[xs.length - 1] >= 115 - 2 * px, `from the start to the end: ${xs[0]}…${xs[xs.length - 1]}`);
    for (let i = 1; i < xs.length; i++) assert.ok(Math.abs(xs[i] - xs[i - 1] - 5) < 0.05 + 2 * px, `spacing σ: ${xs[i] - xs[i - 1]}`);
    // The whole stroke is one undo step.
    await page.keyboard.press('Control+z');
    assert.equal((await comps(page)).length, 0);
    await page.keyboard.press('Control+Shift+z');
    assert.equal((await comps(page)).length, g.length);
  });

  test('Shift + drag erases the components under the brush, one undo step', async () => {
    const before = await comps(page);
    const view0 = await viewState(page);
    await page.keyboard.down('Shift');
    await stroke(page, [70, 55], [70, 95], 12);
    await page.keyboard.up('Shift');
    assert.deepEqual(await viewState(page), view0, 'erasing never pans');
    const now = await comps(page);
    const under = before.filter((c) => Math.abs(c.x - 70) <= 5);
    assert.ok(under.length >= 2, `some under the brush: ${under.length}`);
    assert.equal(now.length, before.length - under.length, 'exactly those under the brush go');
    assert.ok(now.every((c) => Math.abs(c.x - 70) > 5));
    assert.match(await page.getAttribute('#undo', 'title'), new RegExp(`Undo erase ${under.length} Gaussians`));
    // A stroke for the picture: a diagonal band, the brush hovering.
    await stroke(page, [30, 30], [120, 130], 30);
    const p = await mapPoint(page, 125, 135);
    await page.mouse.move(p.x, p.y);
    mkdirSync(shotsDir, { recursive: true });
    await page.screenshot({ path: join(shotsDir, 'tools-brush.png') });
    await page.click('#pdm-save');
    await page.waitForFunction(() => /saved/.test(document.getElementById('pdm-save-status').textContent));
    assert.deepEqual(errors, []);
    await context.close();
  });

  test("the mission form picks the map's latest PDM and warns when a search has none", async () => {
    const maps = await (await fetch(`${ctx.server.url}/api/maps`)).json();
    const latest = await postJson(`${ctx.server.url}/api/maps/${maps[0].id}/pdms`, { name: 'latest', random: 4, seed: 7 });
    ({ page, context, errors } = await openPage(ctx.browser, `${ctx.server.url}/`));
    await waitForMap(page);
    await page.click('#tab-mission');
    assert.equal(await page.inputValue('#m-pdm'), latest.id, 'the most recently saved PDM');
    assert.equal(await page.evaluate(() => window.__roverplanApp.state.pdmId), latest.id, 'and the map shows it');
    await page.selectOption('#m-planner', 'team-search');
    assert.equal(await page.isVisible('#m-pdm-note'), false);
    await page.selectOption('#m-pdm', '');
    assert.equal(await page.isVisible('#m-pdm-note'), true);
    assert.match(await page.textContent('#m-pdm-note'), /team-search without a PDM/);
    // The choice of "none" stays while the list is redrawn.
    await page.evaluate(() => window.__roverplanApp.state.emit('pdms', window.__roverplanApp.state.pdms));
    assert.equal(await page.inputValue('#m-pdm'), '');
    await page.selectOption('#m-planner', 'coverage');
    assert.equal(await page.isVisible('#m-pdm-note'), false, 'coverage needs no PDM');
    assert.deepEqual(errors, []);
    await context.close();
  });
});
