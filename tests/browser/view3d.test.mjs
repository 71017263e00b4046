// The 3D view (issue 27): the toolbar's +/− zoom the 3D camera (they did nothing there), "fit"
// frames the map again, and the map's saved keep-out zones stand on the terrain as red walls.
import assert from 'node:assert/strict';
import { mkdirSync } from 'node:fs';
import { join } from 'node:path';
import { test } from 'node:test';
import { openPage, repoRoot, screenshot, suiteWithServer, waitForMap } from './lib/harness.mjs';

const shotsDir = process.env.ROVERPLAN_SHOTS || join(repoRoot, '..', 'shots');

suiteWithServer('3D view', { timeout: 180000 }, (ctx) => {
  test('+/− zoom the 3D view, fit frames the map, keep-out zones are drawn', async (t) => {
    const maps = await (await fetch(`${ctx.server.url}/api/maps`)).json();
    const map = maps[0].id;
    // Two zones in local metres on the 150 m default map.
    const zones = {
      type: 'FeatureCollection',
      features: [
        { type: 'Feature', properties: { name: 'crater rim' }, geometry: { type: 'Polygon', coordinates: [[[40, 40], [80, 40], [80, 70], [40, 70], [40, 40]]] } },
        { type: 'Feature', properties: {}, geometry: { type: 'Polygon', coordinates: [[[100, 100], [130, 105], [115, 130], [100, 100]]] } },
      ],
    };
    const put = await fetch(`${ctx.server.url}/api/maps/${map}/zones`, { method: 'PUT', headers: { 'content-type': 'application/json' }, body: JSON.stringify(zones) });
    assert.ok(put.ok, `PUT zones: ${put.status} ${await put.text()}`);
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.waitForFunction(() => window.__roverplanApp.state.zones?.features?.length === 2);
    await page.click('#view-3d');
    await page.waitForFunction(() => window.__roverplan.view3dReady || !document.getElementById('view3d-message').hidden, null, { timeout: 30000 });
    const message = await page.evaluate(() => (document.getElementById('view3d-message').hidden ? '' : document.getElementById('view3d-message').textContent));
    if (message) return t.skip(`3D view: ${message}`);
    // The zones: a draped outline and a wall each.
    assert.equal(await page.evaluate(() => window.__roverplan.view3dZones), 2);
    const objects = await page.evaluate(() => window.__roverplanApp.view3d.group.children.filter((o) => o.name === 'zone').length);
    assert.equal(objects, 4);
    const dist = () => page.evaluate(() => window.__roverplanApp.view3d.orbit.dist);
    const d0 = await dist();
    await page.click('#zoom-in');
    const d1 = await dist();
    assert.ok(Math.abs(d1 - d0 / 1.25) < 1e-6 * d0, `+ : ${d0} → ${d1}`);
    await page.click('#zoom-in');
    await page.click('#zoom-in');
    await page.waitForTimeout(200);
    mkdirSync(shotsDir, { recursive: true });
    await page.screenshot({ path: join(shotsDir, 'results-3d-zones.png') });
    await screenshot(page, 'results-3d-zones');
    await page.click('#zoom-out');
    assert.ok(Math.abs((await dist()) - (d0 / 1.25 ** 3) / 0.8) < 1e-6 * d0);
    await page.click('#zoom-fit');
    assert.ok(Math.abs((await dist()) - d0) < 1e-6 * d0, 'fit: the starting distance again');
    // The 2D map's zoom is left alone while the 3D view is shown.
    const scale = await page.evaluate(() => window.__roverplanApp.view.scale);
    await page.click('#zoom-in');
    assert.equal(await page.evaluate(() => window.__roverplanApp.view.scale), scale);
    // Zones removed: the walls go too.
    await fetch(`${ctx.server.url}/api/maps/${map}/zones`, { method: 'PUT', headers: { 'content-type': 'application/json' }, body: JSON.stringify({ type: 'FeatureCollection', features: [] }) });
    await page.evaluate(() => {
      const s = window.__roverplanApp.state;
      s.zones = { type: 'FeatureCollection', features: [] };
      s.emit('zones', s.zones);
    });
    assert.equal(await page.evaluate(() => window.__roverplan.view3dZones), 0);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
