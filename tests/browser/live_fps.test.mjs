// The live view on a big grid: the default 600×600 map at its own 0.25 m cells (360,000 coverage
// cells), pace 2000 steps/s, coverage goal 0.5. Prints the frames per second the page renders
// (window.__roverplan.fps); asserts only that frames arrived — timing depends on the machine.
import assert from 'node:assert/strict';
import { test } from 'node:test';
import { openPage, screenshot, suiteWithServer, waitForMap } from './lib/harness.mjs';

suiteWithServer('live view on a 600×600 grid', { timeout: 240000 }, (ctx) => {
  test('streams and renders a 360,000-cell coverage mission', async () => {
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.click('#tab-mission');
    const map = await page.evaluate(() => window.__roverplanApp.state.map);
    // Two rovers, placed through the form's own fields (the click path is covered elsewhere).
    await page.evaluate(([w, h]) => {
      const f = window.__roverplanApp.missionForm;
      f.rovers = [{ x: w * 0.3, y: h * 0.3, heading: 0 }, { x: w * 0.7, y: h * 0.7, heading: 90 }];
      f.setPlacing(false);
      f.renderRovers();
    }, [map.width_m, map.height_m]);
    await page.fill('#m-param-coverage_cell', '0.25');
    await page.fill('#m-param-coverage', '0.5');
    await page.fill('#m-pace', '2000');
    await page.click('#m-launch');
    await page.waitForFunction(() => window.__roverplan.fullGridFrames > 0, null, { timeout: 60000 });
    const grid = await page.evaluate(() => [window.__roverplanApp.missionView.coverage.rows, window.__roverplanApp.missionView.coverage.cols]);
    assert.deepEqual(grid, [600, 600]);
    // Measure over 5 s of the live run.
    const start = await page.evaluate(() => ({ renders: window.__roverplan.liveRenders, frames: window.__roverplan.gridFrames, t: performance.now() }));
    const samples = [];
    for (let i = 0; i < 10; i++) {
      await page.waitForTimeout(500);
      samples.push(await page.evaluate(() => window.__roverplan.fps));
    }
    const end = await page.evaluate(() => ({ renders: window.__roverplan.liveRenders, frames: window.__roverplan.gridFrames, t: performance.now(), live: window.__roverplanApp.missionView.stream.live }));
    const seconds = (end.t - start.t) / 1000;
    const fps = (end.renders - start.renders) / seconds;
    console.log(`live view, 600×600 grid: ${fps.toFixed(1)} fps rendered over ${seconds.toFixed(1)} s (window.__roverplan.fps samples: ${samples.join(' ')}), ${((end.frames - start.frames) / seconds).toFixed(1)} grid frames/s received${end.live ? '' : ' (the mission ended during the measurement)'}`);
    await screenshot(page, 'live-600x600');
    assert.ok(end.frames > 1, 'grid frames arrived');
    assert.ok(end.renders > start.renders || !end.live, 'the live view rendered');
    if (end.live) {
      await page.click('#live-cancel');
      await page.waitForFunction(() => window.__roverplan.doneFrames > 0, null, { timeout: 60000 });
    }
    assert.deepEqual(errors, []);
    await context.close();
  });
});
