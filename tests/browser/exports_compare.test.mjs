// Issue 13: exports a GIS user can use — the dock's export buttons download result.geojson,
// result.csv, map.png and map.tif, and GDAL's own tools (ogrinfo, gdalinfo) open each download
// with the counts result.json gives; and compare that compares — two team runs side by side:
// every metric with its difference, both runs' curves on one chart, the A/B switch changing the
// map (and the mission the dock shows).
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import { mkdirSync, mkdtempSync, readFileSync, rmSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { test } from 'node:test';
import { openPage, postJson, screenshot, suiteWithServer, waitEnded, waitForMap } from './lib/harness.mjs';

const SHOTS = process.env.SHOTS_DIR || '/work/wt/shots';
const run = (cmd, args) => execFileSync(cmd, args, { encoding: 'utf8' });

suiteWithServer('exports and compare', { timeout: 300000 }, (ctx) => {
  let map, pdm;
  const teamRun = async (targets, seed, name) => {
    const m = await postJson(`${ctx.server.url}/api/missions`, {
      map: map.id, pdm: pdm.id, planner: 'team-search', name, pace: 0,
      rovers: [{ x: 70, y: 70, heading: 0 }, { x: 73, y: 70, heading: 90 }], params: { targets, seed },
    });
    const ended = await waitEnded(ctx.server.url, m.id);
    assert.match(ended.status, /^(succeeded|completed_with_warnings)$/);
    return ended;
  };

  test('the export buttons download files that ogrinfo and gdalinfo open, matching result.json', async () => {
    map = (await (await fetch(`${ctx.server.url}/api/maps`)).json())[0];
    pdm = await postJson(`${ctx.server.url}/api/maps/${map.id}/pdms`, { name: 'three spots', random: 3, seed: 4 });
    const team = await teamRun(3, 1, 'team three targets');
    const result = await (await fetch(`${ctx.server.url}/api/missions/${team.id}/result.json`)).json();

    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.click('#tab-runs');
    await page.click(`#run-list li[data-mission="${team.id}"] button.name`);
    await page.waitForSelector('#export-map-tif:not(.disabled)');
    const dir = mkdtempSync(join(tmpdir(), 'roverplan-exports-'));
    const files = {};
    for (const [button, name] of [['#export-geojson', 'result.geojson'], ['#export-csv', 'result.csv'], ['#export-map-png', 'map.png'], ['#export-map-tif', 'map.tif'], ['#export-mcap', 'replay.mcap']]) {
      const [download] = await Promise.all([page.waitForEvent('download'), page.click(button)]);
      assert.equal(download.suggestedFilename(), `mission-${team.id}-${name}`);
      files[name] = join(dir, download.suggestedFilename());
      await download.saveAs(files[name]);
    }
    // The MCAP replay: the file's magic at both ends (tests/mcap reads it back with @mcap/core).
    const mcap = readFileSync(files['replay.mcap']);
    const magic = Buffer.from([0x89, 0x4d, 0x43, 0x41, 0x50, 0x30, 0x0d, 0x0a]);
    assert.ok(mcap.subarray(0, 8).equals(magic) && mcap.subarray(mcap.length - 8).equals(magic));
    // GeoJSON: layer "mission" in the map's CRS; features per kind as result.json counts them.
    const info = run('ogrinfo', ['-ro', '-al', '-so', files['result.geojson']]);
    assert.match(info, /^Layer name: mission$/m);
    assert.match(info, /PROJCRS\["Mars Equirectangular"/);
    const count = (kind) => (run('ogrinfo', ['-ro', '-al', '-q', '-where', `layer='${kind}'`, files['result.geojson']]).match(/^OGRFeature/gm) || []).length;
    assert.equal(count('track'), result.rovers.length);
    assert.equal(count('route'), 1);
    assert.equal(count('target'), result.targets.length);
    assert.equal(count('incident'), result.incidents.length);
    // CSV: every 10 Hz sample of both rovers, in both frames.
    const csvInfo = run('ogrinfo', ['-ro', '-al', '-so', files['result.csv']]);
    const samples = result.rovers.reduce((n, r) => n + r.metrics.samples, 0);
    assert.match(csvInfo, new RegExp(`^Feature Count: ${samples}$`, 'm'));
    assert.match(csvInfo, /^easting_m: /m);
    assert.match(csvInfo, /^pitch_deg: /m);
    // map.tif: georeferenced in the map's CRS at the DEM's own 600 × 600 pixels; map.png: legends below.
    const tif = run('gdalinfo', [files['map.tif']]);
    assert.match(tif, /^Size is 600, 600$/m);
    assert.match(tif, /PROJCRS\["Mars Equirectangular"/);
    assert.match(tif, /^Pixel Size = \(0\.25/m);
    const png = run('gdalinfo', [files['map.png']]);
    const [, w, h] = png.match(/^Size is (\d+), (\d+)$/m);
    assert.equal(Number(w), 600);
    assert.ok(Number(h) > 600, `map.png ${w}×${h}: no legend below the map`);
    rmSync(dir, { recursive: true, force: true });
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('compare two team runs: every metric with its difference, curves together, A/B map switch', async () => {
    const a = (await (await fetch(`${ctx.server.url}/api/missions`)).json()).find((m) => m.planner === 'team-search');
    const b = await teamRun(4, 2, 'team four targets');
    const results = await Promise.all([a, b].map(async (m) => (await fetch(`${ctx.server.url}/api/missions/${m.id}/result.json`)).json()));

    const { page, errors, context } = await openPage(ctx.browser, `${ctx.server.url}/`);
    await waitForMap(page);
    await page.click('#tab-runs');
    await page.waitForSelector(`#run-list li[data-mission="${b.id}"]`);
    for (const m of [a, b]) await page.check(`#run-list li[data-mission="${m.id}"] input[type="checkbox"]`);
    await page.click('#runs-compare');
    await page.waitForSelector('#compare-view:not([hidden]) #compare-metrics');
    await page.waitForFunction((id) => document.getElementById('compare-map-img')?.dataset.run === id && document.getElementById('compare-map-img').complete
      && document.getElementById('compare-map-img').naturalWidth > 0, a.id);

    // Every metric of either run is a row; where both have it, B − A is shown.
    const rows = await page.$$eval('#compare-metrics tbody tr', (trs) => trs.map((tr) => ({
      key: tr.dataset.metric, cells: [...tr.querySelectorAll('td')].map((td) => td.textContent),
    })));
    const keys = new Set([...Object.keys(results[0].metrics), ...Object.keys(results[1].metrics)]);
    assert.deepEqual(new Set(rows.map((r) => r.key)), keys);
    assert.ok(keys.has('accumulated_probability') && keys.has('targets_reached') && keys.has('collisions'));
    for (const r of rows) {
      const va = results[0].metrics[r.key], vb = results[1].metrics[r.key];
      if (typeof va !== 'number' || typeof vb !== 'number') continue;
      const d = r.cells[2];
      if (va === vb) assert.match(d, /^0$/, `${r.key}: B − A of equal values`);
      else assert.match(d, vb > va ? /^\+/ : /^-/, `${r.key}: B − A = ${d} for ${va} → ${vb}`);
    }
    const targets = rows.find((r) => r.key === 'targets');
    assert.deepEqual(targets.cells.slice(0, 3), ['3', '4', '+1']);
    // The probability curve and the per-rover pitch of both runs on the same axes.
    assert.ok(await page.isVisible('canvas[data-curve="probability_vs_distance_team"]'));
    assert.ok(await page.isVisible('canvas[data-curve="pitch_deg_rover_"]'));
    // The dock shows run A, the one on the map (not a third mission).
    assert.equal(await page.evaluate(() => window.__roverplanApp.missionView.mission?.id), a.id);
    mkdirSync(SHOTS, { recursive: true });
    await page.screenshot({ path: join(SHOTS, 'compare-team-a.png') });
    await screenshot(page, 'compare-team-a');

    // The switch: map B in the panel, on the main map and in the dock.
    await page.click('#compare-show-b');
    await page.waitForFunction((id) => document.getElementById('compare-map-img')?.dataset.run === id
      && window.__roverplanApp.missionView.mission?.id === id, b.id);
    assert.equal(await page.getAttribute('#compare-show-b', 'aria-selected'), 'true');
    assert.match(await page.textContent('#compare-map-caption'), /^B: team four targets/);
    await page.waitForFunction(() => document.getElementById('compare-map-img').complete);
    await page.screenshot({ path: join(SHOTS, 'compare-team-b.png') });
    await page.click('#compare-close');
    assert.equal(await page.isHidden('#compare-view'), true);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
