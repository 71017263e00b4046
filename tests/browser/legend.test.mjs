// Readable results (issue 27) at 1366×768: the legend the page draws itself (elevation ramp with
// ticks, slope ramp, traversability classes, coverage states) lies fully in view, without
// scrolling; obstacle and "4+ visits" differ; the coverage opacity slider changes the paint; a
// team route's target numbers never overlap and the hovered one shows.
import assert from 'node:assert/strict';
import { mkdirSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { test } from 'node:test';
import { mapPoint, openPage, postJson, repoRoot, suiteWithServer, waitEnded } from './lib/harness.mjs';

const shotsDir = resolve(repoRoot, '../shots');
const VIEWPORT = { width: 1366, height: 768 };

function rgb(css) {
  const m = /rgba?\(([\d.]+),\s*([\d.]+),\s*([\d.]+)/.exec(css);
  return m ? [Number(m[1]), Number(m[2]), Number(m[3])] : null;
}

suiteWithServer('legend and route labels', { timeout: 240000 }, (ctx) => {
  let maps;

  test('at 1366×768 every legend of a coverage run is fully in view', async () => {
    maps = await (await fetch(`${ctx.server.url}/api/maps`)).json();
    const m = await postJson(`${ctx.server.url}/api/missions`, {
      map: maps[0].id, planner: 'coverage', pace: 0, rovers: [{ x: 30, y: 40, heading: 0 }, { x: 100, y: 100, heading: 0 }], params: { coverage: 0.3 },
    });
    await waitEnded(ctx.server.url, m.id);
    const { page, context, errors } = await openPage(ctx.browser, `${ctx.server.url}/#mission=${m.id}`, { viewport: VIEWPORT });
    await page.waitForFunction(() => window.__roverplan?.doneFrames > 0 && window.__roverplanApp.missionView.result, null, { timeout: 60000 });
    await page.check('#layer-slope');
    await page.check('#layer-traversability');
    await page.waitForSelector('#legend-list [data-layer="elevation"] canvas.legend-drawn');
    await page.waitForSelector('#legend-list [data-layer="coverage"]');
    const layersShown = await page.evaluate(() => [...document.querySelectorAll('#legend-list .legend-item')].map((n) => n.dataset.layer));
    console.log(`# legends shown: ${layersShown.join(', ')}`);
    for (const id of ['elevation', 'slope', 'traversability', 'coverage', 'trails']) assert.ok(layersShown.includes(id), `${id} legend`);
    // Fully in view: no scrolling inside the panel, every item inside the panel, the map and the window.
    const fit = await page.evaluate(() => {
      const panel = document.getElementById('legend-panel');
      const p = panel.getBoundingClientRect(), map = document.getElementById('map-view').getBoundingClientRect();
      const out = [...panel.querySelectorAll('.legend-item, .legend-item canvas, .legend-class')].filter((n) => {
        const r = n.getBoundingClientRect();
        return r.top < p.top - 0.5 || r.bottom > p.bottom + 0.5 || r.left < p.left - 0.5 || r.right > p.right + 0.5 ||
          r.bottom > map.bottom || r.right > map.right || r.bottom > innerHeight || r.right > innerWidth || n.scrollWidth > n.clientWidth + 1;
      }).map((n) => n.textContent || n.className);
      return { scroll: panel.scrollHeight - panel.clientHeight, out, panel: [p.left, p.top, p.right, p.bottom], layers: document.getElementById('layers-panel').getBoundingClientRect().right };
    });
    assert.equal(fit.scroll, 0, 'the legend does not scroll');
    assert.deepEqual(fit.out, [], 'every legend item lies whole in view');
    assert.ok(fit.panel[0] > fit.layers, 'the legend does not cover the layer list');
    // The elevation ramp: ticks labelled in metres; traversability: class names with their shares.
    assert.match(await page.textContent('#legend-list [data-layer="elevation"]'), /2–98 % of the heights/);
    const classes = await page.textContent('#legend-list [data-layer="traversability"]');
    for (const name of ['traversable', 'high risk', 'impassable', 'nodata']) assert.ok(classes.includes(name), name);
    // Coverage: obstacle and 4+ visits far apart in colour.
    const swatches = await page.evaluate(() => Object.fromEntries([...document.querySelectorAll('#legend-list [data-layer="coverage"] .legend-class')]
      .map((n) => [n.textContent.trim(), getComputedStyle(n.querySelector('.swatch')).backgroundColor])));
    assert.deepEqual(Object.keys(swatches), ['sensed free', 'obstacle', '1 visit', '2 visits', '3 visits', '4+ visits']);
    const [a, b] = [rgb(swatches.obstacle), rgb(swatches['4+ visits'])];
    const dist = Math.hypot(a[0] - b[0], a[1] - b[1], a[2] - b[2]);
    console.log(`# obstacle ${swatches.obstacle} vs 4+ visits ${swatches['4+ visits']}: RGB distance ${dist.toFixed(0)}`);
    assert.ok(dist > 150, `distinct colours: ${dist}`);
    mkdirSync(shotsDir, { recursive: true });
    await page.screenshot({ path: join(shotsDir, 'tools-legend.png') });
    // The coverage opacity slider: the painted grid (an OpenLayers image layer, issue 24) fades
    // with it: OL paints the layer's canvas at the layer's opacity, so the alpha summed over its
    // cells follows the slider (the finished run's grid does not change meanwhile).
    const alphaSum = () => page.evaluate(() => {
      const c = document.querySelector('.map-ol .coverage-grid canvas');
      if (!c || !c.width) return 0;
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let sum = 0;
      for (let i = 3; i < d.length; i += 4) sum += d[i];
      return sum;
    });
    await page.waitForFunction(() => document.querySelector('.map-ol .coverage-grid canvas'), null, { timeout: 10000 });
    const full = await alphaSum();
    assert.equal(await page.evaluate(() => window.__roverplanApp.missionView.coverage.olLayer.getOpacity()), 0.6, 'coverage paints at 60 % by default');
    assert.ok(full > 255 * 1000, `grid cells painted: alpha sum ${full}`);
    await page.fill('#layer-coverage-opacity', '0.25');
    await page.dispatchEvent('#layer-coverage-opacity', 'input');
    await page.waitForFunction((f) => {
      const c = document.querySelector('.map-ol .coverage-grid canvas');
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let sum = 0;
      for (let i = 3; i < d.length; i += 4) sum += d[i];
      return sum < f * 0.6;
    }, full, { timeout: 10000 });
    const faded = await alphaSum();
    console.log(`# coverage grid alpha at 0.6: ${full}, at 0.25: ${faded} (ratio ${(faded / full).toFixed(3)}, 0.417 expected)`);
    assert.ok(Math.abs(faded / full - 0.25 / 0.6) < 0.05, `faded to ${(faded / full).toFixed(3)} of 0.6`);
    assert.deepEqual(errors, []);
    await context.close();
  });

  test("a team route's target numbers do not overlap; the hovered one shows", async () => {
    const m = await postJson(`${ctx.server.url}/api/missions`, {
      map: maps[0].id, planner: 'team-search', pace: 0, params: { targets: 64 },
      rovers: [{ x: 30, y: 40, heading: 0 }, { x: 100, y: 100, heading: 45 }],
    });
    await waitEnded(ctx.server.url, m.id);
    const { page, context, errors } = await openPage(ctx.browser, `${ctx.server.url}/#mission=${m.id}`, { viewport: VIEWPORT });
    await page.waitForFunction(() => window.__roverplanApp.missionView.result && window.__roverplanApp.missionView.plan.route.length > 1, null, { timeout: 60000 });
    await page.evaluate(() => window.__roverplanApp.view.render());
    const state = () => page.evaluate(() => {
      const { plan } = window.__roverplanApp.missionView;
      const v = window.__roverplanApp.view;
      return { n: plan.route.length - 1, labelled: plan.labelled.slice(), route: plan.route, screen: plan.route.map(([x, y]) => v.worldToScreen(x, y)) };
    });
    const s = await state();
    console.log(`# ${s.n} targets, ${s.labelled.length} numbers drawn at the fitted zoom`);
    // The numbers on the map are the OL text features of the plan's number layer (issue 24).
    const shownNumbers = () => page.evaluate(() => window.__roverplanApp.missionView.plan.ol.numbers.getSource().getFeatures()
      .map((f) => Number(f.getStyle().getText().getText())).sort((a, b) => a - b));
    assert.deepEqual(await shownNumbers(), s.labelled.slice().sort((a, b) => a - b));
    assert.ok(s.labelled.length > 0 && s.labelled.length <= s.n);
    // No two drawn numbers' boxes overlap (10 px tall, ~6 px a digit).
    const boxes = s.labelled.map((i) => [s.screen[i][0] + 4, s.screen[i][1] - 13, 6 * String(i).length, 10]);
    for (let i = 0; i < boxes.length; i++)
      for (let j = i + 1; j < boxes.length; j++) {
        const [a, b] = [boxes[i], boxes[j]];
        assert.ok(!(a[0] < b[0] + b[2] && b[0] < a[0] + a[2] && a[1] < b[1] + b[3] && b[1] < a[1] + a[3]), `numbers ${s.labelled[i]} and ${s.labelled[j]} overlap`);
      }
    // Hover a target whose number was hidden: it shows.
    const hidden = Array.from({ length: s.n }, (_, i) => i + 1).find((i) => !s.labelled.includes(i));
    if (hidden) {
      const p = await mapPoint(page, s.route[hidden][0], s.route[hidden][1]);
      await page.mouse.move(p.x, p.y);
      await page.waitForFunction((i) => window.__roverplanApp.missionView.plan.labelled.includes(i), hidden);
      assert.ok((await shownNumbers()).includes(hidden), 'the hovered number is on the map');
    }
    assert.deepEqual(errors, []);
    await context.close();
  });
});
