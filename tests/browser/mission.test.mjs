// A coverage mission from the page: rovers placed by clicking (heading by dragging), parameters
// checked in the page and by the server (its 400 shown next to the right input), launched and
// watched live (frames counted by the page), final metrics, replay with the slider, exports,
// the runs list with two runs compared, and cancelling.
import assert from 'node:assert/strict';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, mapPoint, missingPrerequisite, openPage, screenshot, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);

const counters = (page) => page.evaluate(() => ({ ...window.__roverplan, errors: [...window.__roverplan.errors] }));

async function placeRovers(page, points) {
  for (const [x, y, hx, hy] of points) {
    const p = await mapPoint(page, x, y);
    await page.mouse.move(p.x, p.y);
    await page.mouse.down();
    if (hx !== undefined) {
      const q = await mapPoint(page, hx, hy);
      await page.mouse.move(q.x, q.y, { steps: 6 });
    }
    await page.mouse.up();
  }
}

describe('coverage mission', { skip: missing || false, timeout: 300000 }, () => {
  let server, browser, page, context, errors;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
    ({ page, context, errors } = await openPage(browser, `${server.url}/`, { ignore: [/status of 400/] }));
    await waitForMap(page);
  });
  after(async () => {
    await context?.close();
    await browser?.close();
    await server?.stop();
  });

  test('two rovers are placed by clicking, the second heading set by dragging', async () => {
    await page.click('#tab-mission');
    assert.equal(await page.getAttribute('#m-place', 'aria-pressed'), 'true', 'placing starts with unplaced rovers');
    // Both on traversable ground: a start on impassable ground is refused (issue 11).
    await placeRovers(page, [[30, 40], [100, 100, 110, 110]]);
    const rovers = await page.evaluate(() => window.__roverplanApp.missionForm.rovers);
    assert.equal(rovers.length, 2);
    assert.ok(Math.abs(rovers[0].x - 30) < 0.5 && Math.abs(rovers[0].y - 40) < 0.5, JSON.stringify(rovers[0]));
    assert.ok(Math.abs(rovers[1].heading - 45) <= 2, `heading from the drag: ${rovers[1].heading}`);
    assert.equal(await page.getAttribute('#m-place', 'aria-pressed'), 'false', 'placing ends when all are placed');
    // Every parameter of the planner is in the form with its default and doc.
    const planners = await (await fetch(`${server.url}/api/planners`)).json();
    const coverage = planners.find((p) => p.name === 'coverage');
    for (const info of coverage.params) {
      assert.ok(await page.$(`#m-param-${info.key}`), `input for ${info.key}`);
      assert.match(await page.getAttribute(`#m-param-${info.key}`, 'title'), new RegExp(`default`));
    }
    assert.equal(await page.inputValue('#m-param-coverage'), String(coverage.params.find((p) => p.key === 'coverage').default));
    await screenshot(page, 'mission-form');
  });

  test('out-of-range values are caught in the page, server refusals shown at their input', async () => {
    await page.fill('#m-param-coverage', '2');
    await page.click('#m-launch');
    assert.match(await page.textContent('[data-field="params.coverage"]'), /at most 1/);
    assert.equal(await page.evaluate(() => document.getElementById('m-param-coverage').classList.contains('invalid')), true);
    // alpha + beta = 1 is the server's rule: its 400 lands next to beta.
    await page.fill('#m-param-coverage', '0.3');
    await page.fill('#m-param-alpha', '0.5');
    await page.fill('#m-param-beta', '0.2');
    await page.click('#m-launch');
    await page.waitForSelector('#m-error:not([hidden])');
    await page.waitForFunction(() => document.querySelector('[data-field="params.beta"]').textContent.length > 0);
    const text = await page.textContent('[data-field="params.beta"]');
    console.log(`server error at params.beta: ${text}`);
    assert.match(text, /alpha \+ beta/);
    assert.match(await page.textContent('#m-error'), /field: params\.beta/);
    await screenshot(page, 'mission-server-error');
    await page.fill('#m-param-alpha', '1');
    await page.fill('#m-param-beta', '0');
  });

  test('launch: streamed frames arrive and the final metrics show', async () => {
    await page.fill('#m-pace', '2000');
    await page.fill('#m-param-coverage', '0.3');
    await page.click('#m-launch');
    await page.waitForFunction(() => window.__roverplan.gridFrames > 0, null, { timeout: 30000 });
    await screenshot(page, 'mission-live');
    await page.waitForFunction(() => window.__roverplan.doneFrames > 0, null, { timeout: 120000 });
    await page.waitForFunction(() => !document.getElementById('replay-slider').disabled, null, { timeout: 30000 });
    const c = await counters(page);
    console.log(`stream: ${c.wsMessages} messages, ${c.fullGridFrames} full + ${c.diffGridFrames} diff grid frames, ${c.posesFrames} poses, ${c.progressFrames} progress; live view peak ${c.fpsPeak} fps`);
    assert.equal(c.missionStatus, 'succeeded');
    assert.ok(c.fullGridFrames >= 1, 'a full grid frame');
    assert.ok(c.finalMetrics && c.finalMetrics.coverage >= 0.3, `final coverage ${c.finalMetrics?.coverage}`);
    assert.match(await page.textContent('#metrics [data-metric="coverage"]'), /%/);
    assert.match(await page.textContent('#live-status'), /succeeded/);
    assert.equal(await page.evaluate(() => document.getElementById('live-progress').value), 1);
    await page.waitForTimeout(300);
    await screenshot(page, 'mission-done');
    // The trails draped on the terrain in the 3D view.
    await page.click('#view-3d');
    await page.waitForFunction(() => window.__roverplan.view3dReady || !document.getElementById('view3d-message').hidden, null, { timeout: 30000 });
    if (await page.evaluate(() => window.__roverplan.view3dReady)) {
      await page.waitForFunction(() => window.__roverplanApp.view3d.group.children.filter((o) => o.name === 'trail').length === 2);
      await page.waitForTimeout(500);
      await screenshot(page, 'mission-3d');
    }
    await page.click('#view-map');
  });

  test('replay via the slider moves the rovers back and trims the trails', async () => {
    const max = Number(await page.getAttribute('#replay-slider', 'max'));
    assert.ok(max > 10);
    const mid = Math.round(max / 3);
    await page.focus('#replay-slider');
    await page.evaluate((v) => {
      const s = document.getElementById('replay-slider');
      s.value = String(v);
      s.dispatchEvent(new Event('input', { bubbles: true }));
    }, mid);
    await page.keyboard.press('ArrowRight');  // keyboard works on the slider too
    const state = await page.evaluate(() => {
      const mv = window.__roverplanApp.missionView;
      return { limit: mv.trails.limit, pose: mv.trails.poseOf(0), path: mv.result.rovers[0].path, step: window.__roverplan.replayStep };
    });
    assert.equal(state.step, mid + 1);
    assert.equal(state.limit, mid + 1);
    assert.deepEqual([state.pose.x, state.pose.y], state.path[Math.min(mid + 1, state.path.length - 1)]);
    assert.match(await page.textContent('#replay-label'), new RegExp(`step ${mid + 1} / ${max}`));
    await screenshot(page, 'mission-replay');
    await page.click('#replay-play');
    await page.waitForTimeout(400);
    await page.click('#replay-play');
  });

  test('exports: GeoJSON and CSV links answer, the download happens, PNG of the map', async () => {
    const href = await page.getAttribute('#export-geojson', 'href');
    assert.match(href, /result\.geojson$/);
    const r = await fetch(server.url + href);
    assert.equal(r.status, 200);
    const geo = await r.json();
    assert.equal(geo.type, 'FeatureCollection');
    const csv = await fetch(server.url + (await page.getAttribute('#export-csv', 'href')));
    assert.equal(csv.status, 200);
    assert.match(await csv.text(), /^rover,move,x_m,y_m,easting_m,northing_m,/);
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-geojson')]);
    assert.match(download.suggestedFilename(), /result\.geojson$/);
    const [png] = await Promise.all([page.waitForEvent('download'), page.click('#export-png')]);
    assert.match(png.suggestedFilename(), /\.png$/);
  });

  test('the runs list shows parameters; two runs compare side by side', async () => {
    // A second run: one rover, boustrophedon.
    await page.click('#tab-mission');
    await page.fill('#m-rover-count', '1');
    await page.dispatchEvent('#m-rover-count', 'input');
    await page.selectOption('#m-param-pattern', 'boustrophedon');
    await page.click('#m-launch');
    await page.waitForFunction(() => window.__roverplan.doneFrames >= 2, null, { timeout: 120000 });
    await page.click('#tab-runs');
    await page.waitForFunction(() => document.querySelectorAll('#run-list li[data-mission]').length === 2);
    assert.match(await page.textContent('#run-list'), /pattern=boustrophedon/);
    assert.match(await page.textContent('#run-list'), /coverage=0\.3/);
    const boxes = page.locator('#run-list li[data-mission] input[type="checkbox"]');
    await boxes.nth(0).check();
    await boxes.nth(1).check();
    await page.click('#runs-compare');
    await page.waitForSelector('#compare-view:not([hidden]) #compare-metrics');
    const table = await page.textContent('#compare-metrics');
    assert.match(table, /path length ratio/);
    await page.waitForSelector('#compare-map-img[src]');
    await page.waitForTimeout(300);
    await screenshot(page, 'runs-compare');
    await page.click('#compare-close');
    assert.equal(await page.isHidden('#compare-view'), true);
    // Open a finished run from the list: its stream replays the stored state.
    const before = (await counters(page)).doneFrames;
    await page.click('#run-list li[data-mission] button.name');
    await page.waitForFunction((n) => window.__roverplan.doneFrames > n, before, { timeout: 30000 });
  });

  test('a running mission can be cancelled', async () => {
    await page.click('#tab-mission');
    await page.fill('#m-pace', '20');
    await page.click('#m-launch');
    await page.waitForFunction(() => !document.getElementById('live-cancel').disabled, null, { timeout: 30000 });
    await page.click('#live-cancel');
    await page.waitForFunction(() => window.__roverplan.missionStatus === 'cancelled', null, { timeout: 30000 });
    assert.match(await page.textContent('#live-status'), /cancelled/);
    assert.deepEqual(errors, []);
  });
});
