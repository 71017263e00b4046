// The route profile (issue 27): a team mission whose attitude limit (exceedance_limit 5°) is
// crossed; the profile of a rover chosen by clicking its trail holds exactly its result.json
// samples (roll, pitch; distance along its path), marks exactly the samples over the limit and
// every exceedance incident's time; hovering the chart moves the map's marker; CSV and PNG export.
import assert from 'node:assert/strict';
import { mkdirSync, readFileSync } from 'node:fs';
import { join, resolve } from 'node:path';
import { test } from 'node:test';
import { mapPoint, openPage, postJson, repoRoot, suiteWithServer, waitEnded, waitForMap } from './lib/harness.mjs';

const shotsDir = resolve(repoRoot, '../shots');

suiteWithServer('route profile', { timeout: 240000 }, (ctx) => {
  let page, context, errors, result, missionId;

  test('a rover chosen by clicking its trail: the profile is its samples', async () => {
    const maps = await (await fetch(`${ctx.server.url}/api/maps`)).json();
    const m = await postJson(`${ctx.server.url}/api/missions`, {
      map: maps[0].id, planner: 'team-search', pace: 0, params: { exceedance_limit: 5, targets: 16 },
      rovers: [{ x: 30, y: 40, heading: 0 }, { x: 100, y: 100, heading: 45 }],
    });
    missionId = m.id;
    const ended = await waitEnded(ctx.server.url, m.id);
    assert.match(ended.status, /completed/);
    result = await (await fetch(`${ctx.server.url}/api/missions/${m.id}/result.json`)).json();
    assert.ok(result.metrics.exceedances > 0, 'the run crosses its 5° limit');

    ({ page, context, errors } = await openPage(ctx.browser, `${ctx.server.url}/#mission=${m.id}`, { viewport: { width: 1366, height: 768 } }));
    await waitForMap(page);
    await page.waitForFunction(() => !document.getElementById('profile-rover').disabled);
    await page.waitForFunction(() => window.__roverplanApp.layers.rasters.elevation);
    // Click the second rover's trail at a point of its path away from the other's.
    const k = 1, path = result.rovers[k].path;
    const other = result.rovers[0].path;
    const far = path.findIndex((p, j) => j > 20 && other.every((q) => Math.hypot(q[0] - p[0], q[1] - p[1]) > 4));
    assert.ok(far > 0);
    const at = await mapPoint(page, path[far][0], path[far][1]);
    await page.mouse.click(at.x, at.y);
    await page.waitForFunction(() => window.__roverplanApp.routeProfile.data?.rover === 1);
    assert.equal(await page.getAttribute('#dock-tab-profile', 'aria-selected'), 'true', 'the profile tab opens');
    assert.equal(await page.inputValue('#profile-rover'), '1');

    const d = await page.evaluate(() => window.__roverplanApp.routeProfile.data);
    const pitch = result.series[`pitch_deg_rover_${k}`], roll = result.series[`roll_deg_rover_${k}`];
    assert.deepEqual(d.pitch, pitch.y, 'pitch: the result samples');
    assert.deepEqual(d.roll, roll.y, 'roll: the result samples');
    assert.deepEqual(d.t, pitch.x);
    // Distance: along the rover's path to the sample's point (one a second).
    const cum = [0];
    for (let j = 1; j < path.length; j++) cum.push(cum[j - 1] + Math.hypot(path[j][0] - path[j - 1][0], path[j][1] - path[j - 1][1]));
    pitch.x.forEach((t, i) => {
      const j = Math.min(path.length - 1, Math.round(t));
      assert.ok(Math.abs(d.d[i] - cum[j]) < 1e-6, `distance of sample ${i}`);
      assert.deepEqual([d.x[i], d.y[i]], path[j]);
    });
    const { min, max } = maps[0].elevation;
    assert.ok(d.elevation.every((z) => z !== null && z >= min - 1e-3 && z <= max + 1e-3), 'elevations from the map');
    // Marks: exactly the samples past the mission's attitude limit.
    const limit = result.metrics.attitude_limit_deg;
    assert.equal(d.limit, limit);
    const over = pitch.y.map((p, i) => Math.max(Math.abs(p), Math.abs(roll.y[i])) > limit);
    assert.deepEqual(d.over, over);
    const marked = over.filter(Boolean).length;
    console.log(`# rover ${k + 1}: ${d.d.length} samples, ${cum[cum.length - 1].toFixed(1)} m, ${marked} over ${limit}°`);
    assert.ok(marked > 0);
    // Every exceedance incident of this rover falls on a marked sample (within the 1 s sampling).
    const incidents = result.incidents.filter((it) => it.kind === 'exceedance' && it.rover === k);
    assert.ok(incidents.length > 0);
    for (const it of incidents) assert.ok(over.some((o, i) => o && Math.abs(pitch.x[i] - it.time_s) <= 1), `incident at ${it.time_s} s marked`);
    assert.match(await page.textContent('#profile-summary'), new RegExp(`${marked} samples over`));
  });

  test('hovering the chart moves the marker on the map', async () => {
    const box = await page.locator('#profile-chart').boundingBox();
    // The pitch panel (the fourth), at 60 % of its width.
    await page.mouse.move(box.x + box.width * (0.75 + 0.25 * 0.6), box.y + box.height / 2);
    await page.waitForFunction(() => window.__roverplanApp.routeProfile.hover >= 0);
    const h = await page.evaluate(() => {
      const p = window.__roverplanApp.routeProfile;
      return { i: p.hover, n: p.data.d.length, x: p.data.x[p.hover], y: p.data.y[p.hover] };
    });
    assert.ok(h.i > h.n * 0.4 && h.i < h.n * 0.8, `a sample in the middle of the track: ${h.i} of ${h.n}`);
    assert.match(await page.textContent('#profile-readout'), /elevation .* m · slope .* · roll .* · pitch/);
    mkdirSync(shotsDir, { recursive: true });
    await page.screenshot({ path: join(shotsDir, 'tools-profile.png') });
    // Another place on the chart: the marker follows.
    await page.mouse.move(box.x + box.width * (0.75 + 0.25 * 0.2), box.y + box.height / 2);
    await page.waitForFunction((i) => window.__roverplanApp.routeProfile.hover !== i, h.i);
  });

  test('in the 3D view the hovered sample is a ball on the terrain', async () => {
    await page.click('#view-3d');
    await page.waitForFunction(() => window.__roverplan.view3dReady, null, { timeout: 60000 });
    const box = await page.locator('#profile-chart').boundingBox();
    await page.mouse.move(box.x + box.width * (0.75 + 0.25 * 0.5), box.y + box.height / 2);
    await page.waitForFunction(() => window.__roverplanApp.view3d.marker?.parent);
    const m = await page.evaluate(() => {
      const { view3d, routeProfile: p } = window.__roverplanApp;
      const { W, H } = view3d.extent;
      return { px: view3d.marker.position.x, pz: view3d.marker.position.z, x: p.data.x[p.hover] - W / 2, z: H / 2 - p.data.y[p.hover] };
    });
    assert.ok(Math.abs(m.px - m.x) < 1e-6 && Math.abs(m.pz - m.z) < 1e-6, JSON.stringify(m));
    await page.screenshot({ path: join(shotsDir, 'tools-profile-3d.png') });
    await page.mouse.move(box.x + 2, box.y - 20);  // off the chart: the ball goes
    await page.waitForFunction(() => !window.__roverplanApp.view3d.marker);
    await page.click('#view-map');
  });

  test('the profile exports as CSV (its samples) and PNG', async () => {
    const d = await page.evaluate(() => window.__roverplanApp.routeProfile.data);
    const [csvDl] = await Promise.all([page.waitForEvent('download'), page.click('#profile-csv')]);
    assert.match(csvDl.suggestedFilename(), new RegExp(`${missionId}-rover2-profile\\.csv$`));
    const lines = readFileSync(await csvDl.path(), 'utf8').trim().split('\n');
    assert.equal(lines[0], 'rover,time_s,distance_m,x_m,y_m,elevation_m,slope_along_track_deg,roll_deg,pitch_deg,over_attitude_limit');
    assert.equal(lines.length, d.d.length + 1);
    const cols = lines[1 + 10].split(',');
    assert.equal(Number(cols[0]), 2, 'rovers numbered from 1');
    assert.ok(Math.abs(Number(cols[8]) - d.pitch[10]) < 1e-4);
    assert.equal(lines.filter((l) => l.endsWith(',1')).length, d.over.filter(Boolean).length);
    const [pngDl] = await Promise.all([page.waitForEvent('download'), page.click('#profile-png')]);
    const png = readFileSync(await pngDl.path());
    assert.deepEqual([...png.subarray(1, 4)], [0x50, 0x4e, 0x47]);
    assert.ok(png.length > 5000, `a picture: ${png.length} bytes`);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
