// The mission form and the upload form (issue 13): parameters in the sections of the planner's
// own table with the common ones first and the rest folded, numbers rounded, the planner's
// presets; the layout at 1280×800 and 1366×768 with no panel over another (element boxes
// checked); a real DEM uploaded from the page with a crop and a vertical scale.
import assert from 'node:assert/strict';
import { existsSync, readFileSync } from 'node:fs';
import { join } from 'node:path';
import { test } from 'node:test';
import { openPage, screenshot, sharedDems, suiteWithServer, waitForMap } from './lib/harness.mjs';

// Rectangles overlap when they share more than a pixel in both directions.
const overlaps = (a, b) => a.x < b.x + b.width - 1 && b.x < a.x + a.width - 1 && a.y < b.y + b.height - 1 && b.y < a.y + a.height - 1;

async function missionTab(page, planner) {
  await page.click('#tab-mission');
  await page.selectOption('#m-planner', planner);
  await page.waitForSelector(`#m-params fieldset.param-group`);
}

// What the form shows: sections in order, and per section the visible and folded parameters.
const formShape = (page) => page.evaluate(() => [...document.querySelectorAll('#m-params fieldset.param-group')].map((f) => ({
  group: f.dataset.group,
  shown: [...f.querySelectorAll(':scope > .param')].map((p) => p.dataset.param),
  folded: [...f.querySelectorAll(':scope > details .param')].map((p) => p.dataset.param),
  open: f.querySelector(':scope > details')?.open ?? false,
})));

suiteWithServer('mission and upload forms', { timeout: 240000 }, (ctx) => {
  test('team-search: sections from the table, common parameters first, the rest folded, numbers rounded', async () => {
    const planners = await (await fetch(`${ctx.server.url}/api/planners`)).json();
    const team = planners.find((p) => p.name === 'team-search');
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await missionTab(page, 'team-search');
    const shape = await formShape(page);
    // The sections and their order are the table's.
    const groups = [...new Set(team.params.map((p) => p.group))];
    assert.deepEqual(shape.map((s) => s.group), groups);
    assert.deepEqual(groups.slice(0, 5), ['route', 'RRT*', 'coordination', 'rover', 'simulation']);
    for (const s of shape) {
      const table = team.params.filter((p) => p.group === s.group);
      assert.deepEqual(s.shown, table.filter((p) => p.level === 'common').map((p) => p.key), `${s.group}: common shown`);
      assert.deepEqual(s.folded, table.filter((p) => p.level !== 'common').map((p) => p.key), `${s.group}: the rest folded`);
      assert.equal(s.open, false);
    }
    const shown = shape.reduce((n, s) => n + s.shown.length, 0);
    console.log(`team-search: ${team.params.length} parameters, ${shown} shown in ${shape.length} sections, the rest folded`);
    assert.ok(shown <= 16 && shown >= 8, `${shown} shown`);
    // Float noise is gone (exceedance_limit is 15° stored in radians and converted back).
    const values = await page.$$eval('#m-params input[type="number"]', (ns) => ns.map((n) => [n.id, n.value]));
    const noisy = values.filter(([, v]) => /\.\d{7,}|e-/.test(v));
    assert.deepEqual(noisy, []);
    assert.equal(await page.inputValue('#m-param-exceedance_limit'), '15');
    assert.equal(await page.inputValue('#m-param-n_phi'), '15');
    // A parameter left as shown is not sent: the form sends nothing for the defaults.
    assert.deepEqual(await page.evaluate(() => window.__roverplanApp.missionForm.readParams()), { params: {}, errors: [] });
    const panel = await page.$eval('#panel-mission', (p) => p.scrollHeight);
    console.log(`mission panel height with the sections folded: ${panel} px`);
    await screenshot(page, 'form-team-1280x800');
    // Unfolding shows the rest; an error on a folded parameter unfolds its section.
    await page.click('fieldset[data-group="RRT*"] > details > summary');
    assert.equal(await page.isVisible('#m-param-goal_bias'), true);
    await page.click('fieldset[data-group="RRT*"] > details > summary');
    // A value out of range in a folded parameter (set by a preset or a mission file, say).
    await page.evaluate(() => { document.getElementById('m-param-n_psi').value = '1000'; });
    await page.click('#m-launch');
    await page.waitForFunction(() => document.querySelector('fieldset[data-group="RRT*"] > details').open);
    assert.match(await page.textContent('.field-error[data-field="params.n_psi"]'), /at most 180/);
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('presets from the server fill the form in: paper 001, fast preview, and coverage paper 002', async () => {
    const planners = await (await fetch(`${ctx.server.url}/api/planners`)).json();
    const team = planners.find((p) => p.name === 'team-search');
    assert.deepEqual(team.presets.map((p) => p.name), ['paper 001', 'fast preview']);
    assert.deepEqual(planners.find((p) => p.name === 'coverage').presets.map((p) => p.name), ['paper 002', 'fast preview']);
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await missionTab(page, 'team-search');
    await page.selectOption('#m-preset', 'paper 001');
    assert.equal(await page.inputValue('#m-param-coordination'), 'paper');
    assert.equal(await page.inputValue('#m-param-max_vertices'), '1250');
    assert.equal(await page.inputValue('#m-param-targets'), '64');
    assert.equal(await page.isChecked('#m-param-slip'), true);
    assert.match(await page.textContent('#m-preset-doc'), /Swinton/);
    // What is sent: the preset's values that differ from the defaults, nothing else.
    const paper = team.presets.find((p) => p.name === 'paper 001').params;
    const sent = (await page.evaluate(() => window.__roverplanApp.missionForm.readParams())).params;
    for (const [k, v] of Object.entries(sent)) assert.deepEqual(v, paper[k], k);
    assert.equal(sent.coordination, 'paper');
    await screenshot(page, 'form-team-paper001');
    // Another preset starts again from the defaults.
    await page.selectOption('#m-preset', 'fast preview');
    assert.equal(await page.inputValue('#m-param-coordination'), 'timed');
    assert.equal(await page.inputValue('#m-param-targets'), '16');
    assert.deepEqual((await page.evaluate(() => window.__roverplanApp.missionForm.readParams())).params,
      team.presets.find((p) => p.name === 'fast preview').params);
    await missionTab(page, 'coverage');
    assert.equal(await page.inputValue('#m-preset'), '');
    await page.selectOption('#m-preset', 'paper 002');
    assert.equal(await page.inputValue('#m-param-pattern'), 'spiral');
    assert.equal(await page.isChecked('#m-param-frontier'), false);
    const shape = await formShape(page);
    assert.deepEqual(shape.map((s) => s.group), ['motion', 'cost', 'grid', 'energy', 'localisation']);
    await screenshot(page, 'form-coverage-1280x800');
    assert.deepEqual(errors, []);
    await context.close();
  });

  for (const viewport of [{ width: 1280, height: 800 }, { width: 1366, height: 768 }]) {
    test(`layout at ${viewport.width}×${viewport.height}: no panel covers another, the form fits its column`, async () => {
      const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`, { viewport });
      await waitForMap(page);
      await page.waitForSelector('#legend-list canvas');
      const boxes = async () => Object.fromEntries(await Promise.all(
        ['.topbar', '.viewer', '.side', '.dock', '#layers-panel', '#legend-panel', '.view-toolbar', '.readout', '.tabs']
          .map(async (sel) => [sel, await page.locator(sel).first().boundingBox()])));
      const check = async (what) => {
        const b = await boxes();
        for (const [k, r] of Object.entries(b)) {
          assert.ok(r, `${k} is shown (${what})`);
          assert.ok(r.x >= -1 && r.y >= -1 && r.x + r.width <= viewport.width + 1 && r.y + r.height <= viewport.height + 1,
            `${k} ${JSON.stringify(r)} lies inside the window (${what})`);
        }
        // The screen's regions tile it; the floating panels stay apart and inside the map.
        const regions = ['.topbar', '.viewer', '.side', '.dock'];
        for (let i = 0; i < regions.length; i++)
          for (let j = i + 1; j < regions.length; j++)
            assert.ok(!overlaps(b[regions[i]], b[regions[j]]), `${regions[i]} / ${regions[j]} overlap (${what})`);
        assert.ok(!overlaps(b['#layers-panel'], b['#legend-panel']), `layers / legend overlap (${what})`);
        for (const f of ['#layers-panel', '#legend-panel'])
          assert.ok(!overlaps(b[f], b['.side']) && !overlaps(b[f], b['.dock']) && !overlaps(b[f], b['.readout']), `${f} leaves the map (${what})`);
        // Every control of the side panel's visible tab lies inside the panel's column.
        const outside = await page.evaluate(() => {
          const side = document.querySelector('.side').getBoundingClientRect();
          return [...document.querySelectorAll('.side .panel:not([hidden]) input, .side .panel:not([hidden]) select, .side .panel:not([hidden]) button')]
            .filter((n) => n.offsetParent !== null && n.type !== 'file')
            .filter((n) => { const r = n.getBoundingClientRect(); return r.left < side.left - 1 || r.right > side.right + 1; })
            .map((n) => n.id || n.outerHTML.slice(0, 60));
        });
        assert.deepEqual(outside, [], what);
      };
      await check('maps tab');
      await page.click('#dem-options > summary');
      await check('maps tab, upload options open');
      await missionTab(page, 'team-search');
      await check('mission tab');
      // The launch bar stays in view at the bottom of the panel, whatever is scrolled.
      const bar = await page.locator('.launch-bar').boundingBox();
      const side = await page.locator('.side').boundingBox();
      assert.ok(bar.y + bar.height <= side.y + side.height + 1 && bar.y >= side.y, `launch bar ${JSON.stringify(bar)} in ${JSON.stringify(side)}`);
      await screenshot(page, `form-layout-${viewport.width}x${viewport.height}`);
      assert.deepEqual(errors, []);
      await context.close();
    });
  }

  test('upload form: a real DEM with a pixel crop, a vertical scale and a body', async () => {
    const kepler = join(sharedDems, 'moon_lola_kepler_crater/kepler.tif');
    if (!existsSync(kepler)) {
      console.log(`# ${kepler} is absent (no ../shared/dems): upload options test skipped`);
      return;
    }
    // The same file uploaded whole, for the expected numbers.
    const whole = await (await fetch(`${ctx.server.url}/api/maps?filename=kepler.tif&name=whole`, {
      method: 'POST', headers: { 'Content-Type': 'image/tiff' }, body: readFileSync(kepler),
    })).json();
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.setInputFiles('#dem-files', kepler);
    await page.fill('#dem-name', 'Kepler window');
    await page.click('#dem-options > summary');
    await page.selectOption('#dem-crop-unit', 'crop_px');
    await page.fill('#dem-crop', '1,2,3');  // refused on the page, before anything is sent
    await page.click('#dem-upload');
    assert.match(await page.textContent('#dem-error'), /four numbers.*field: crop_px/);
    await page.fill('#dem-crop', '200, 200, 400, 300');
    await page.fill('#dem-vscale', '0.5');
    await page.selectOption('#dem-body', 'moon');
    await page.click('#dem-upload');
    await page.waitForFunction(() => document.getElementById('map-title').textContent.includes('Kepler window'), null, { timeout: 60000 });
    const maps = await (await fetch(`${ctx.server.url}/api/maps`)).json();
    const m = maps.find((x) => x.name === 'Kepler window');
    assert.equal(m.cols, 400);
    assert.equal(m.rows, 300);
    assert.equal(m.vertical_scale, 0.5);
    assert.equal(m.body, 'moon');
    assert.deepEqual(m.crop_px, [200, 200, 400, 300]);
    // Halved heights of a window inside the whole map's range.
    assert.ok(m.elevation.min >= whole.elevation.min * 0.5 - 1e-6 && m.elevation.max <= whole.elevation.max * 0.5 + 1e-6,
      `${JSON.stringify(m.elevation)} within half of ${JSON.stringify(whole.elevation)}`);
    assert.ok(m.elevation.max - m.elevation.min > 10);
    const info = await page.textContent('#map-info');
    assert.match(info, /400 × 300 cells/);
    assert.match(info, /moon \(declared at upload\)/);
    assert.match(info, /pixels 200, 200, 400, 300 · heights × 0\.5/);
    await page.waitForFunction(() => window.__roverplan.layersLoaded.filter((l) => l === 'elevation').length >= 2, null, { timeout: 30000 });
    await page.waitForTimeout(300);
    await screenshot(page, 'form-upload-options');
    // A server refusal lands on its field: a window outside the file.
    await page.setInputFiles('#dem-files', kepler);
    await page.fill('#dem-crop', '700,700,400,300');
    await page.click('#dem-upload');
    await page.waitForFunction(() => !document.getElementById('dem-error').hidden, null, { timeout: 60000 });
    assert.match(await page.textContent('#dem-error'), /outside.*field: crop_px/);
    assert.equal(await page.getAttribute('#dem-crop', 'class'), 'invalid');
    assert.deepEqual(errors.filter((e) => !/400 \(Bad Request\)/.test(e)), []);
    await context.close();
  });

  test('upload form: a file of lunar radii gets a warning naming the offset; the offset fixes it', async () => {
    const site = join(sharedDems, 'moon_kepler_rescaled_025m/kepler_site.tif');
    if (!existsSync(site)) {
      console.log(`# ${site} is absent (no ../shared/dems): scale warning test skipped`);
      return;
    }
    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    // The site shifted up by the Moon's radius stands for a cube of radii (issue 27).
    await page.setInputFiles('#dem-files', site);
    await page.fill('#dem-name', 'Kepler radii');
    await page.click('#dem-options > summary');
    await page.fill('#dem-voffset', '1737400');
    await page.click('#dem-upload');
    await page.waitForFunction(() => document.getElementById('map-title').textContent.includes('Kepler radii'), null, { timeout: 60000 });
    assert.match(await page.textContent('#dem-warnings'), /look like radii of the Moon .*vertical_offset=-1737400/);
    assert.match(await page.textContent('#map-info'), /heights \+ 1[ ,.]?737[ ,.]?400 m/);
    assert.match(await page.textContent('#map-info'), /look like radii of the Moon/);
    assert.match(await page.textContent('#m-scale-note'), /vertical_offset=-1737400/);
    await screenshot(page, 'form-scale-warning');
    // Uploaded again with no offset: heights, and no warning anywhere.
    await page.setInputFiles('#dem-files', site);
    await page.fill('#dem-name', 'Kepler heights');
    await page.fill('#dem-voffset', '0');
    await page.click('#dem-upload');
    await page.waitForFunction(() => document.getElementById('map-title').textContent.includes('Kepler heights'), null, { timeout: 60000 });
    assert.equal(await page.textContent('#dem-warnings'), '');
    assert.equal(await page.textContent('#m-scale-note'), '');
    assert.deepEqual(errors, []);
    await context.close();
  });
});
