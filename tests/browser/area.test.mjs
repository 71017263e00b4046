// The mission area drawn on the map (issue 24): a rectangle dragged on the 2D map fills the
// mission form's area field (rounded to the map's cells), Escape drops a drawing, "clear" empties
// the field; a coverage mission launched with it plans in it: the mission's area.bbox is the
// drawn rectangle and every trajectory point of result.json lies inside it.
import assert from 'node:assert/strict';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, mapPoint, missingPrerequisite, openPage, startServer, waitEnded, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);

const fieldBbox = async (page) => (await page.inputValue('#m-area')).split(',').map((s) => Number(s.trim()));

// Drags on the map from local point a to b (metres), pressing Escape before the release when asked.
async function drag(page, a, b, { escape = false } = {}) {
  const p = await mapPoint(page, a[0], a[1]);
  const q = await mapPoint(page, b[0], b[1]);
  await page.mouse.move(p.x, p.y);
  await page.mouse.down();
  await page.mouse.move(q.x, q.y, { steps: 6 });
  if (escape) await page.keyboard.press('Escape');
  await page.mouse.up();
}

describe('mission area drawn on the map', { skip: missing || false, timeout: 300000 }, () => {
  let server, browser;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  test('a dragged rectangle fills the area field, Escape and clear work, a coverage mission stays inside it', async () => {
    const { page, errors, context } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    const map = await page.evaluate(() => window.__roverplanApp.state.map);
    const cw = map.cell_size_m, ch = map.cell_height_m ?? map.cell_size_m;
    await page.click('#tab-mission');
    // The default map is small: the note says an area is optional; a map over 4096² cells needs one.
    assert.match(await page.textContent('#m-area-note'), /^Optional on this map/);
    const bigNote = await page.evaluate(() => {
      const t = window.__roverplanApp.areaTool;
      t.renderNote({ rows: 7000, cols: 7000 });
      const text = document.getElementById('m-area-note').textContent;
      t.renderNote(window.__roverplanApp.state.map);
      return text;
    });
    assert.match(bigNote, /7000 × 7000 cells, more than a mission plans whole/);

    await page.selectOption('#m-planner', 'coverage');
    await page.fill('#m-rover-count', '1');

    // Escape during a drag: nothing drawn, the tool disarmed, the field untouched.
    await page.click('#m-area-draw');
    assert.equal(await page.getAttribute('#m-area-draw', 'aria-pressed'), 'true');
    await drag(page, [20, 20], [60, 60], { escape: true });
    assert.equal(await page.inputValue('#m-area'), '');
    assert.equal(await page.evaluate(() => window.__roverplanApp.state.tool), 'pan');
    assert.equal(await page.getAttribute('#m-area-draw', 'aria-pressed'), 'false');

    // A drag from the north-east corner to the south-west one: the field holds x0 < x1, y0 < y1,
    // each on a cell corner within a cell of the pointer's point.
    const a = [101.3, 96.7], b = [41.2, 38.9];
    await page.click('#m-area-draw');
    await drag(page, a, b);
    const drawn = await fieldBbox(page);
    assert.equal(drawn.length, 4, await page.inputValue('#m-area'));
    const px = await page.evaluate(() => 1 / window.__roverplanApp.view.scale);  // metres per CSS pixel
    const want = [b[0], b[1], a[0], a[1]];
    drawn.forEach((v, i) => {
      const cell = i % 2 ? ch : cw;
      assert.ok(Math.abs(v / cell - Math.round(v / cell)) < 1e-6, `${v} is on a cell corner (${cell} m)`);
      assert.ok(Math.abs(v - want[i]) <= cell / 2 + 2 * px, `corner ${i}: ${v} vs ${want[i]}`);
    });
    assert.deepEqual(await page.evaluate(() => window.__roverplanApp.areaTool.outline), drawn);
    assert.equal(await page.evaluate(() => window.__roverplanApp.state.tool), 'pan', 'the tool disarms after a rectangle');
    await page.screenshot({ path: '/tmp/area.png' });

    // Typing moves the outline; clear empties both.
    await page.fill('#m-area', '10, 20, 30, 40');
    assert.deepEqual(await page.evaluate(() => window.__roverplanApp.areaTool.outline), [10, 20, 30, 40]);
    await page.click('#m-area-clear');
    assert.equal(await page.inputValue('#m-area'), '');
    assert.equal(await page.evaluate(() => window.__roverplanApp.areaTool.outline), null);
    await page.fill('#m-area', drawn.join(', '));
    assert.deepEqual(await page.evaluate(() => window.__roverplanApp.areaTool.outline), drawn);

    // A small coverage mission, one rover inside the area.
    await page.fill('#m-param-coverage', '0.2');
    await page.fill('#m-pace', '0');
    if ((await page.getAttribute('#m-place', 'aria-pressed')) !== 'true') await page.click('#m-place');
    const s = await mapPoint(page, (drawn[0] + drawn[2]) / 2, (drawn[1] + drawn[3]) / 2);
    await page.mouse.click(s.x, s.y);
    const posted = page.waitForResponse((r) => r.url().endsWith('/api/missions') && r.request().method() === 'POST', { timeout: 30000 });
    await page.click('#m-launch');
    const response = await posted;
    const launched = await response.json();
    assert.equal(response.status(), 202, `launch refused: ${JSON.stringify(launched)} ${await page.textContent('#m-error')}`);
    const m = await waitEnded(server.url, launched.id);
    assert.ok(['succeeded', 'completed_with_warnings'].includes(m.status), `${m.status}: ${m.message}`);
    assert.deepEqual(m.spec.area, { bbox: drawn }, 'the mission as sent');
    const result = await (await fetch(`${server.url}/api/missions/${launched.id}/result.json`)).json();
    assert.deepEqual(result.area, { bbox: drawn });
    let points = 0;
    for (const r of result.rovers) {
      for (const [x, y] of r.path) {
        points++;
        assert.ok(x >= drawn[0] - 1e-9 && x <= drawn[2] + 1e-9 && y >= drawn[1] - 1e-9 && y <= drawn[3] + 1e-9, `point (${x}, ${y}) outside ${drawn}`);
      }
    }
    console.log(`area ${drawn.join(', ')} m: ${points} trajectory points, all inside; coverage ${result.metrics?.coverage}`);
    assert.ok(points > 10, `too few trajectory points (${points})`);

    // The mission shown carries its area, outlined on the map in the Runs view as well.
    await page.waitForFunction((id) => window.__roverplanApp.missionView.mission?.id === id, launched.id, { timeout: 30000 });
    assert.deepEqual(await page.evaluate(() => window.__roverplanApp.areaTool.missionArea()), { bbox: drawn });
    await page.click('#tab-runs');
    await page.screenshot({ path: '/tmp/area-runs.png' });
    // Duplicate and edit: the mission file keeps the area, the form and its outline get it back.
    await page.evaluate(() => window.__roverplanApp.areaTool.clear());  // the form is hidden in Runs
    await page.locator(`#run-list li[data-mission="${launched.id}"] button[aria-label^="duplicate"]`).click();
    await page.waitForFunction(() => document.getElementById('m-area').value !== '', null, { timeout: 30000 });
    assert.deepEqual(await fieldBbox(page), drawn);
    assert.deepEqual(await page.evaluate(() => window.__roverplanApp.areaTool.outline), drawn);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
