// The PDM editor: two Gaussians added by clicking, one dragged, its sigma handle pulled, saved;
// then the server's layer for the saved PDM is shown, and random (G=4) works.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { mapPoint, openPage, screenshot, suiteWithServer, waitForMap } from './lib/harness.mjs';

const comps = (page) => page.evaluate(() => window.__roverplanApp.pdmEditor.comps.map((g) => ({ ...g })));

suiteWithServer('PDM editor', { timeout: 180000 }, (ctx) => {
  test('add two components by clicking, drag one, save, see the saved PDM layer', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.click('#tab-pdm');
    for (const [x, y] of [[40, 50], [105, 110]]) {
      const p = await mapPoint(page, x, y);
      await page.mouse.click(p.x, p.y);
    }
    let g = await comps(page);
    assert.equal(g.length, 2);
    assert.ok(Math.abs(g[0].x - 40) < 1 && Math.abs(g[0].y - 50) < 1, `first component at (40, 50): ${JSON.stringify(g[0])}`);
    // Drag the first one's centre to (60, 35).
    const a = await mapPoint(page, g[0].x, g[0].y), b = await mapPoint(page, 60, 35);
    await page.mouse.move(a.x, a.y);
    await page.mouse.down();
    await page.mouse.move(b.x, b.y, { steps: 10 });
    await page.mouse.up();
    g = await comps(page);
    assert.ok(Math.abs(g[0].x - 60) < 1 && Math.abs(g[0].y - 35) < 1, `dragged to (60, 35): ${JSON.stringify(g[0])}`);
    assert.equal(g.length, 2, 'a drag adds nothing');
    // Pull the second one's σx handle out to 20 m (rotation 0: the handle is east of the centre).
    const h = await mapPoint(page, g[1].x + g[1].sigma_x, g[1].y), h2 = await mapPoint(page, g[1].x + 20, g[1].y);
    await page.mouse.move(h.x, h.y);
    await page.mouse.down();
    await page.mouse.move(h2.x, h2.y, { steps: 6 });
    await page.mouse.up();
    g = await comps(page);
    assert.ok(Math.abs(g[1].sigma_x - 20) < 0.5, `σx pulled to 20 m: ${g[1].sigma_x}`);
    // On the map the components are OpenLayers features (issue 24): each centre handle where its
    // Gaussian is, the σx handle on its axis at the new σx.
    await page.waitForFunction(() => window.__roverplanApp.pdmEditor.olHandles.parts.length === 2);
    const handles = await page.evaluate(() => window.__roverplanApp.pdmEditor.olHandles.parts.map((q) => ({
      centre: q.centre.getGeometry().getCoordinates(), sx: q.sx.getGeometry().getCoordinates() })));
    g.forEach((c, i) => {
      assert.ok(Math.hypot(handles[i].centre[0] - c.x, handles[i].centre[1] - c.y) < 1e-6, `centre handle ${i}: ${handles[i].centre}`);
    });
    assert.ok(Math.abs(handles[1].sx[0] - (g[1].x + g[1].sigma_x)) < 1e-6 && Math.abs(handles[1].sx[1] - g[1].y) < 1e-6, `σx handle on its axis: ${handles[1].sx}`);
    // A weight typed in the panel.
    await page.fill('[data-key="1.weight"]', '2');
    await page.dispatchEvent('[data-key="1.weight"]', 'change');
    assert.equal((await comps(page))[1].weight, 2);
    assert.equal(await page.evaluate(() => window.__roverplanApp.pdmEditor.showOverlay()), true, 'the density overlay shows while editing');
    await screenshot(page, 'pdm-editing');
    await page.fill('#pdm-name', 'two spots');
    await page.click('#pdm-save');
    await page.waitForFunction(() => window.__roverplan.layersLoaded.includes('pdm'), null, { timeout: 30000 });
    await page.waitForSelector('#legend-list [data-layer="pdm"] canvas');
    assert.match(await page.textContent('#pdm-list li.selected'), /two spots/);
    assert.equal(await page.evaluate(() => window.__roverplanApp.pdmEditor.showOverlay()), false, 'the server layer replaces the overlay');
    // The saved PDM on the server holds the edited components.
    const pdmId = await page.evaluate(() => window.__roverplanApp.state.pdmId);
    const mapId = await page.evaluate(() => window.__roverplanApp.state.map.id);
    const saved = await (await fetch(`${ctx.server.url}/api/maps/${mapId}/pdms/${pdmId}`)).json();
    assert.equal(saved.components.length, 2);
    assert.ok(Math.abs(saved.components[0].x - 60) < 1);
    const png = await fetch(`${ctx.server.url}/api/maps/${mapId}/layers/pdm.png?pdm=${pdmId}`);
    assert.equal(png.status, 200);
    // The readout gains the PDM value.
    await page.waitForFunction(() => window.__roverplanApp.layers.rasters.pdm);
    const p = await mapPoint(page, 60, 35);
    await page.mouse.move(p.x, p.y);
    await page.mouse.move(p.x + 1, p.y);
    assert.match(await page.textContent('#readout'), /PDM \d/);
    await screenshot(page, 'pdm-saved');
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('random (G=4) makes a draft of 4 components, saved only on "save"', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    page.on('dialog', (d) => d.accept());  // the draft of the test above is replaced
    await waitForMap(page);
    const mapId = await page.evaluate(() => window.__roverplanApp.state.map.id);
    const count = async () => (await (await fetch(`${ctx.server.url}/api/maps/${mapId}/pdms`)).json()).length;
    const before = await count();
    await page.click('#tab-pdm');
    await page.fill('#pdm-seed', '7');
    await page.click('#pdm-random');
    await page.waitForFunction(() => window.__roverplanApp.pdmEditor.comps.length === 4);
    // Issue 26: a draft, not a saved PDM (it used to be saved by itself).
    assert.equal(await count(), before);
    assert.equal(await page.inputValue('#pdm-name'), 'random G=4 seed 7');
    assert.match(await page.textContent('#pdm-save-status'), /random draft: not saved/);
    const again = await comps(page);
    await page.click('#pdm-random');  // the same seed, the same draft
    assert.deepEqual(await comps(page), again);
    await page.click('#pdm-save');
    await page.waitForFunction(() => /^saved “random G=4 seed 7”/.test(document.getElementById('pdm-save-status').textContent));
    assert.equal(await count(), before + 1);
    assert.match(await page.textContent('#pdm-list li.selected'), /seed 7/);
    await page.click('#pdm-clear');
    assert.equal((await comps(page)).length, 0);
    // Saving nothing is refused in the page.
    await page.click('#pdm-save');
    assert.match(await page.textContent('#pdm-error'), /at least one/);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
