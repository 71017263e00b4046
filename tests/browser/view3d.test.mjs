// The 3D view (issue 27): the toolbar's +/− zoom the 3D camera (they did nothing there), "fit"
// frames the map again, and the map's saved keep-out zones stand on the terrain as red walls.
// On tiles (issue 24): a map bigger than one tile is meshed from its elevation value tiles, and
// zooming in brings the native zoom's tiles around the orbit target.
import assert from 'node:assert/strict';
import { mkdirSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';
import { generatedDem, openPage, repoRoot, screenshot, suiteWithServer, waitForMap } from './lib/harness.mjs';

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
  test('a map bigger than one tile: the mesh comes from elevation tiles, finer ones around the target when zoomed in', async (t) => {
    const work = mkdtempSync(join(tmpdir(), 'roverplan-3d-'));
    t.after(() => rmSync(work, { recursive: true, force: true }));
    const up = await fetch(`${ctx.server.url}/api/maps?name=tiled3d&filename=tiled3d.tif`, {
      method: 'POST', headers: { 'Content-Type': 'image/tiff' }, body: readFileSync(generatedDem(work, 1200)),
    });
    assert.equal(up.status, 201, await up.clone().text());
    const map = await up.json();
    // 1200 cells: zoom 0 one tile, 1 2 × 2, 2 3 × 3, 3 (native, a cell a pixel) 5 × 5.
    assert.equal(map.tiles.native_zoom, 3);
    assert.deepEqual(map.tiles.tile_counts.slice(0, 4), [[1, 1], [2, 2], [3, 3], [5, 5]]);
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/#map=${map.id}`);
    await waitForMap(page);
    await page.waitForFunction(() => document.getElementById('map-title').textContent.includes('tiled3d'));
    // The 2D map's cursor readout loads the whole-map layers; the 3D view must not.
    await page.waitForFunction(() => window.__roverplanApp.layers.rasters.elevation);
    const urls = [];
    page.on('request', (r) => urls.push(new URL(r.url()).pathname));
    await page.click('#view-3d');
    await page.waitForFunction(() => window.__roverplan.view3dReady || !document.getElementById('view3d-message').hidden, null, { timeout: 30000 });
    const message = await page.evaluate(() => (document.getElementById('view3d-message').hidden ? '' : document.getElementById('view3d-message').textContent));
    if (message) return t.skip(`3D view: ${message}`);
    const tileRe = new RegExp(`^/api/maps/${map.id}/tiles/elevation/(\\d+)/(\\d+)/(\\d+)\\.f32$`);
    const tiles = () => urls.map((u) => tileRe.exec(u)).filter(Boolean).map((m) => m.slice(1).map(Number));
    // The base: the deepest zoom whose tiles of the whole map are at most 4 — zoom 1's 2 × 2.
    assert.deepEqual(await page.evaluate(() => window.__roverplan.view3dLevels), [1]);
    assert.deepEqual(tiles().map(([z, x, y]) => `${z}/${x}/${y}`).sort(), ['1/0/0', '1/0/1', '1/1/0', '1/1/1']);
    assert.ok(!urls.some((u) => u.includes('/layers/elevation')), `no whole-map layer: ${urls.filter((u) => u.includes('/layers/'))}`);
    // No cracks: neighbouring tiles' meshes share their edge vertices exactly (257 a side, at the
    // pixel corners, heights from both tiles' pixels).
    const seam = await page.evaluate(() => {
      const meshes = window.__roverplanApp.view3d.group.children.filter((o) => o.name === 'terrain');
      const pos = (x, y) => meshes.find((m) => m.userData.tile.join('/') === `1/${x}/${y}`).geometry.attributes.position.array;
      const a = pos(0, 0), right = pos(1, 0), below = pos(0, 1);
      let worst = 0;
      for (let k = 0; k <= 256; k++) {
        for (let c = 0; c < 3; c++) {
          worst = Math.max(worst, Math.abs(a[3 * (k * 257 + 256) + c] - right[3 * (k * 257) + c]));
          worst = Math.max(worst, Math.abs(a[3 * (256 * 257 + k) + c] - below[3 * k + c]));
        }
      }
      return worst;
    });
    assert.equal(seam, 0, 'shared tile edges');
    const coarse = await canvasStats(page);
    assert.ok(coarse.lit > 0.1 && coarse.colours > 20, `the terrain is drawn: ${JSON.stringify(coarse)}`);
    await screenshot(page, 'view3d-tiles-base');

    // Zoom in on the map's centre (150, 150 m: zoom 3's tile 2, 2) until the native zoom's tiles
    // are asked for: the 3 × 3 of them around the target, nothing deeper. Their answers are held
    // back here, so the view moves on while they are in flight.
    let hold = true, allHeld;
    const held = [], failed = [], nineHeld = new Promise((resolve) => (allHeld = resolve));
    await page.route(/\/tiles\/elevation\/3\/\d+\/\d+\.f32$/, (route) => {
      if (!hold) return route.continue();
      if (held.push(route) === 9) allHeld();
    });
    page.on('requestfailed', (r) => failed.push(new URL(r.url()).pathname));
    for (let i = 0; i < 6; i++) await page.click('#zoom-in');
    await nineHeld;
    const asked = () => tiles().filter(([z]) => z === 3).map(([, x, y]) => `${x}/${y}`).sort();
    assert.deepEqual(asked(), ['1/1', '1/2', '1/3', '2/1', '2/2', '2/3', '3/1', '3/2', '3/3']);
    assert.ok(tiles().every(([z]) => z <= map.tiles.native_zoom));

    // Panning the target to the south-west corner: the window moves there and the fetches of the
    // old one are cancelled.
    hold = false;
    await page.evaluate(() => {
      const v = window.__roverplanApp.view3d;
      v.orbit.target[0] = -v.extent.W / 2 + 10;
      v.orbit.target[2] = v.extent.H / 2 - 10;  // local (10, 10)
      v.frame();
    });
    await page.waitForFunction(() => window.__roverplanApp.view3d.terrain.entries.at(-1)?.key === '3/0/2/3/3', null, { timeout: 30000 });
    assert.deepEqual(await page.evaluate(() => window.__roverplan.view3dLevels), [1, 3]);
    const cancelled = failed.map((u) => tileRe.exec(u)).filter(Boolean).map((m) => m.slice(1).join('/')).sort();
    assert.deepEqual(cancelled, ['3/1/1', '3/1/2', '3/1/3', '3/2/1', '3/2/2', '3/2/3', '3/3/1', '3/3/2', '3/3/3']);
    for (const r of held) await r.continue().catch(() => {});  // answered late, to no one
    const terrain = await page.evaluate(() => window.__roverplanApp.view3d.group.children.filter((o) => o.name === 'terrain').length);
    assert.equal(terrain, 4 + 9, 'the base tiles and the 3 × 3 finer ones');
    assert.equal(await page.evaluate(() => window.__roverplanApp.view3d.group.children.filter((o) => o.name === 'terrain-wall').length), 1,
      'a wall closes the seam between the finer window and the base');
    await screenshot(page, 'view3d-tiles-refined');
    const near = await canvasStats(page);
    assert.ok(near.lit > 0.15 && near.colours > 20, `the refined terrain is drawn (the map's corner: half the view is beyond it): ${JSON.stringify(near)}`);
    // Fit: the whole map again, the finer tiles dropped.
    await page.click('#zoom-fit');
    await page.waitForFunction(() => window.__roverplan.view3dLevels.length === 1, null, { timeout: 30000 });
    assert.equal(await page.evaluate(() => window.__roverplanApp.view3d.group.children.filter((o) => o.name.startsWith('terrain')).length), 4);
    // Traversability colours: the layer's PNG tiles of the base zoom as textures.
    await page.selectOption('#view3d-colour', 'traversability');
    await page.waitForFunction(() => window.__roverplanApp.view3d.group.children.some((o) => o.name === 'terrain' && o.material.map));
    assert.ok(urls.some((u) => u === `/api/maps/${map.id}/tiles/traversability/1/0/0.png`));
    const classes = await canvasStats(page);
    assert.ok(classes.lit > 0.1, `the classes are drawn: ${JSON.stringify(classes)}`);
    assert.deepEqual(errors, []);
    await context.close();
  });
});

// The share of the 3D canvas's pixels that are not the background, and how many distinct colours
// (5 bits a channel) they show, sampled every 7th pixel of a fresh render.
function canvasStats(page) {
  return page.evaluate(() => {
    const v = window.__roverplanApp.view3d;
    v.renderer.render(v.scene, v.camera);
    const src = v.renderer.domElement;
    const c = document.createElement('canvas');
    c.width = src.width;
    c.height = src.height;
    const g = c.getContext('2d');
    g.drawImage(src, 0, 0);
    const d = g.getImageData(0, 0, c.width, c.height).data;
    let n = 0, lit = 0;
    const colours = new Set();
    for (let i = 0; i < d.length; i += 4 * 7) {
      n++;
      if (Math.abs(d[i] - 11) + Math.abs(d[i + 1] - 13) + Math.abs(d[i + 2] - 16) < 12) continue;  // 0x0b0d10
      lit++;
      colours.add(((d[i] >> 3) << 10) | ((d[i + 1] >> 3) << 5) | (d[i + 2] >> 3));
    }
    return { lit: lit / n, colours: colours.size };
  });
}
