// The page's address and layout (issue 13): a live mission's id is in the URL, so a reload or a
// shared link opens it again; choosing another map closes the mission view; at 1280×800 and
// 1366×768 the layers and legend panels do not overlap, every layer row can be clicked, and every
// metric of a finished mission shows its whole value.
import assert from 'node:assert/strict';
import { mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import { generatedDem, launchBrowser, postJson, missingPrerequisite, openPage, screenshot, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);

// Rectangles overlap when they share more than a pixel in both directions.
const overlaps = (a, b) => a.x < b.x + b.width - 1 && b.x < a.x + a.width - 1 && a.y < b.y + b.height - 1 && b.y < a.y + a.height - 1;

describe('address and layout', { skip: missing || false, timeout: 300000 }, () => {
  let server, browser, work, defaultMap;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
    work = mkdtempSync(join(tmpdir(), 'roverplan-address-'));
    defaultMap = (await (await fetch(`${server.url}/api/maps`)).json())[0].id;
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
    if (work) rmSync(work, { recursive: true, force: true });
  });

  test('a reload, and a shared link, open the live mission again', async () => {
    // Slow enough (10 steps/s to 60 %) to be still running across the reload.
    const m = await postJson(`${server.url}/api/missions`, {
      map: defaultMap, planner: 'coverage', pace: 10, rovers: [{ x: 30, y: 40, heading: 0 }], params: { coverage: 0.6 },
    });
    const { page, errors, context } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    await page.click('#tab-runs');
    await page.evaluate((id) => window.__roverplanApp.missionView.show(id), m.id);
    await page.waitForFunction(() => window.__roverplan.gridFrames > 0, null, { timeout: 30000 });
    assert.equal(new URL(page.url()).hash, `#mission=${m.id}`);
    await page.reload();
    await page.waitForFunction((id) => window.__roverplan?.missionId === id && window.__roverplan.gridFrames > 0, m.id, { timeout: 30000 });
    assert.match(await page.textContent('#live-title'), new RegExp(m.id));
    const status = await page.evaluate(() => window.__roverplan.missionStatus);
    console.log(`after the reload: mission ${m.id} ${status}`);
    assert.ok(['running', 'succeeded'].includes(status), status);
    // The same link in a new tab.
    const other = await openPage(browser, `${server.url}/#mission=${m.id}`);
    await other.page.waitForFunction((id) => window.__roverplan?.missionId === id && window.__roverplan.gridFrames > 0, m.id, { timeout: 30000 });
    await screenshot(other.page, 'address-shared-link');
    assert.deepEqual(other.errors, []);
    await other.context.close();
    // A link to a mission that does not exist says so and shows a map.
    const gone = await openPage(browser, `${server.url}/#mission=0000000000000000`, { ignore: [/404/] });
    await waitForMap(gone.page);
    await gone.page.waitForFunction(() => /does not exist/.test(document.getElementById('status-line').textContent));
    await gone.context.close();
    await fetch(`${server.url}/api/missions/${m.id}`, { method: 'DELETE' });
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('choosing another map closes the mission shown on the first', async () => {
    const tif = generatedDem(work, 96);
    const up = await fetch(`${server.url}/api/maps?name=second&filename=terrain.tif`, {
      method: 'POST', headers: { 'Content-Type': 'image/tiff' }, body: readFileSync(tif),
    });
    const second = await up.json();
    assert.ok(up.ok, JSON.stringify(second));
    const m = await postJson(`${server.url}/api/missions`, {
      map: defaultMap, planner: 'coverage', pace: 0, rovers: [{ x: 30, y: 40, heading: 0 }], params: { coverage: 0.2 },
    });
    const { page, errors, context } = await openPage(browser, `${server.url}/#mission=${m.id}`);
    await page.waitForFunction(() => window.__roverplan?.doneFrames > 0, null, { timeout: 60000 });
    assert.equal(await page.evaluate(() => window.__roverplanApp.missionView.trails.paths.length), 1);
    await page.click('#tab-maps');
    await page.click(`#map-list li[data-map="${second.id}"] button.name`);
    await page.waitForFunction(() => /second/.test(document.getElementById('map-title').textContent));
    assert.equal(await page.textContent('#live-title'), 'no mission');
    assert.equal(await page.evaluate(() => window.__roverplanApp.missionView.trails.paths.length), 0);
    assert.equal(await page.isHidden('#live-status'), true);
    assert.equal(await page.textContent('#metrics'), '');
    assert.equal(new URL(page.url()).hash, `#map=${second.id}`);
    await screenshot(page, 'address-map-switch');
    assert.deepEqual(errors, []);
    await context.close();
  });

  for (const viewport of [{ width: 1280, height: 800 }, { width: 1366, height: 768 }]) {
    test(`layout at ${viewport.width}×${viewport.height}: no panel covers another, every metric reads whole`, async () => {
      const m = await postJson(`${server.url}/api/missions`, {
        map: defaultMap, planner: 'coverage', pace: 0, rovers: [{ x: 30, y: 40, heading: 0 }], params: { coverage: 0.3 },
      });
      const { page, errors, context } = await openPage(browser, `${server.url}/#mission=${m.id}`, { viewport });
      await page.waitForFunction(() => window.__roverplan?.doneFrames > 0, null, { timeout: 60000 });
      await page.waitForTimeout(200);
      const layers = await page.locator('#layers-panel').boundingBox();
      const legend = await page.locator('#legend-panel').boundingBox();
      assert.ok(!overlaps(layers, legend), `layers ${JSON.stringify(layers)} / legend ${JSON.stringify(legend)}`);
      // Every layer's checkbox is the element at its own centre: nothing lies over it.
      const covered = await page.evaluate(() => [...document.querySelectorAll('#layer-list input[type="checkbox"]')]
        .filter((box) => {
          const r = box.getBoundingClientRect();
          return document.elementFromPoint(r.left + r.width / 2, r.top + r.height / 2) !== box;
        }).map((box) => box.id || box.closest('.layer-row')?.textContent));
      assert.deepEqual(covered, []);
      // Each metric value fits its cell, and the cell lies inside the dock's status column.
      const cut = await page.evaluate(() => {
        const column = document.querySelector('.dock-status').getBoundingClientRect();
        return [...document.querySelectorAll('#metrics td[data-metric]')].filter((td) => {
          const r = td.getBoundingClientRect();
          return td.scrollWidth > td.clientWidth + 1 || r.right > column.right + 1 || r.left < column.left - 1;
        }).map((td) => `${td.dataset.metric}=${td.textContent}`);
      });
      assert.ok((await page.locator('#metrics td[data-metric]').count()) >= 4);
      assert.deepEqual(cut, []);
      await screenshot(page, `layout-${viewport.width}x${viewport.height}`);
      assert.deepEqual(errors, []);
      await context.close();
    });
  }
});
