// The page loads cleanly, draws the default map, toggles layers, shows the cursor readout, keeps
// its layout at 1280×800 and 1920×1080, and renders the 3D view.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { mapPoint, openPage, screenshot, suiteWithServer, waitForMap } from './lib/harness.mjs';

suiteWithServer('page', { timeout: 180000 }, (ctx) => {
  test('loads without console errors and draws the default map', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    const ms = await waitForMap(page);
    console.log(`page load to first map drawn: ${ms} ms`);
    assert.match(await page.textContent('#map-title'), /Default/);
    // The elevation legend comes from the server PNG's own strip.
    await page.waitForSelector('#legend-list [data-layer="elevation"] canvas');
    await page.waitForTimeout(300);
    await screenshot(page, 'page-1280x800');
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('the traversability layer toggles on and the cursor readout shows a class', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.check('#layer-traversability');
    await page.waitForFunction(() => window.__roverplan.layersLoaded.includes('traversability'));
    await page.waitForFunction(() => window.__roverplanApp.layers.rasters.traversability && window.__roverplanApp.layers.rasters.elevation);
    // The page draws the class legend itself (legend.js): a swatch and a name per class.
    await page.waitForSelector('#legend-list [data-layer="traversability"] .legend-class');
    const p = await mapPoint(page, 75, 75);
    await page.mouse.move(p.x, p.y);
    await page.mouse.move(p.x + 3, p.y + 2);
    const readout = await page.textContent('#readout');
    console.log(`readout: ${readout.replace(/\s+/g, ' ')}`);
    assert.match(readout, /class (traversable|high risk|impassable|nodata)/);
    assert.match(readout, /elevation -?\d/);
    assert.match(readout, /slope \d/);
    // Opacity slider blends the layer.
    await page.fill('#layer-traversability-opacity', '0.3');
    await screenshot(page, 'layer-traversability');
    await page.uncheck('#layer-traversability');
    assert.equal(await page.evaluate(() => window.__roverplanApp.layers.isVisible('traversability')), false);
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('keyboard zoom and tabs work', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    const scale0 = await page.evaluate(() => window.__roverplanApp.view.scale);
    await page.focus('#map-canvas');
    await page.keyboard.press('+');
    const scale1 = await page.evaluate(() => window.__roverplanApp.view.scale);
    assert.ok(scale1 > scale0, 'the + key zooms in');
    await page.keyboard.press('0');
    await page.focus('#tab-maps');
    await page.keyboard.press('ArrowRight');
    assert.equal(await page.getAttribute('#tab-pdm', 'aria-selected'), 'true');
    assert.equal(await page.isVisible('#panel-pdm'), true);
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('the layout holds at 1920×1080 and 1280×800', async () => {
    for (const viewport of [{ width: 1920, height: 1080 }, { width: 1280, height: 800 }]) {
      const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`, { viewport });
      await waitForMap(page);
      await page.waitForTimeout(300);
      await screenshot(page, `layout-${viewport.width}x${viewport.height}`);
      const boxes = await page.evaluate(() => Object.fromEntries(['.viewer', '.side', '.dock', '.topbar', '#map-canvas'].map((s) => {
        const r = document.querySelector(s).getBoundingClientRect();
        return [s, { x: r.x, y: r.y, w: r.width, h: r.height }];
      })));
      const right = (b) => b.x + b.w, bottom = (b) => b.y + b.h;
      assert.ok(right(boxes['.viewer']) <= boxes['.side'].x + 1, 'viewer and side panel do not overlap');
      assert.ok(bottom(boxes['.viewer']) <= boxes['.dock'].y + 1, 'viewer and dock do not overlap');
      assert.ok(right(boxes['.side']) <= viewport.width + 1 && bottom(boxes['.dock']) <= viewport.height + 1, 'nothing spills off screen');
      assert.ok(boxes['#map-canvas'].w >= 600 && boxes['#map-canvas'].h >= 400, `map canvas is usable (${boxes['#map-canvas'].w}×${boxes['#map-canvas'].h})`);
      assert.deepEqual(errors, []);
      await context.close();
    }
  });

  test('the 3D view renders the terrain', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.click('#view-3d');
    await page.waitForFunction(() => window.__roverplan.view3dReady || !document.getElementById('view3d-message').hidden, null, { timeout: 30000 });
    const message = await page.evaluate(() => document.getElementById('view3d-message').hidden ? '' : document.getElementById('view3d-message').textContent);
    if (message) console.log(`3D view: ${message}`);
    else {
      await page.selectOption('#view3d-colour', 'traversability');
      await page.waitForTimeout(1000);
    }
    await screenshot(page, 'view-3d');
    await page.click('#view-map');
    assert.equal(await page.isVisible('#map-canvas'), true);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
