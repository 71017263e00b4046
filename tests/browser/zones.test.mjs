// Keep-out zones from the page (issue 13): a zone drawn with mouse clicks and saved with the map;
// a coverage mission and a small team mission launched with "respect keep-out zones" never put a
// trajectory point inside it (read from result.json).
import assert from 'node:assert/strict';
import { after, before, describe, test } from 'node:test';
import { mkdirSync } from 'node:fs';
import { launchBrowser, mapPoint, missingPrerequisite, openPage, repoRoot, startServer, waitEnded, waitForMap } from './lib/harness.mjs';
import { join, resolve } from 'node:path';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);

const shotsDir = resolve(repoRoot, '../shots');

function inside(ring, x, y) {
  let c = false;
  for (let i = 0, j = ring.length - 1; i < ring.length; j = i++) {
    const [xi, yi] = ring[i], [xj, yj] = ring[j];
    if ((yi > y) !== (yj > y) && x < ((xj - xi) * (y - yi)) / (yj - yi) + xi) c = !c;
  }
  return c;
}

async function shot(page, name) {
  mkdirSync(shotsDir, { recursive: true });
  await page.screenshot({ path: join(shotsDir, `zones-${name}.png`) });
}

// Launches the mission the form holds and waits for its end; returns its result.json.
async function launchAndWait(page, server) {
  await page.fill('#m-pace', '0');
  const posted = page.waitForResponse((r) => r.url().endsWith('/api/missions') && r.request().method() === 'POST', { timeout: 30000 });
  await page.click('#m-launch');
  const refused = await page.waitForFunction(() => !document.getElementById('m-error').hidden, null, { timeout: 2000 }).then(() => true, () => false);
  if (refused) assert.fail(`not launched: ${await page.textContent('#m-error')}`);
  const response = await posted;
  const launched = await response.json();
  assert.equal(response.status(), 202, `launch refused: ${JSON.stringify(launched)} ${await page.textContent('#m-error')}`);
  const id = launched.id;
  const m = await waitEnded(server.url, id);
  assert.ok(['succeeded', 'completed_with_warnings'].includes(m.status), `${m.status}: ${m.message}`);
  assert.ok(m.spec.keep_out, 'the mission was sent with keep_out');
  const result = await (await fetch(`${server.url}/api/missions/${id}/result.json`)).json();
  await page.waitForFunction(() => window.__roverplan.doneFrames > 0, null, { timeout: 60000 }).catch(() => {});
  return { id, result };
}

function checkOutside(result, ring, what) {
  let points = 0, outside = 0;
  for (const r of result.rovers) {
    for (const [x, y] of r.path) {
      points++;
      if (!inside(ring, x, y)) outside++;
    }
  }
  console.log(`${what}: ${points} trajectory points, ${points - outside} inside the zone`);
  assert.ok(points > 10, `${what}: too few points (${points})`);
  assert.equal(outside, points, `${what}: trajectory points inside the zone`);
}

describe('keep-out zones', { skip: missing || false, timeout: 300000 }, () => {
  let server, browser;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  test('a zone drawn with clicks is saved and no coverage or team trajectory enters it', async () => {
    const { page, errors, context } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    const mapId = await page.evaluate(() => window.__roverplanApp.state.map.id);
    // The default map is 150 × 150 m; the zone is a quadrilateral east of the rovers.
    const ring = [[60, 45], [95, 40], [100, 110], [62, 105]];
    await page.click('#zones-draw');
    for (const [x, y] of ring) {
      const p = await mapPoint(page, x, y);
      await page.mouse.click(p.x, p.y);
    }
    const first = await mapPoint(page, ring[0][0], ring[0][1]);
    await page.mouse.click(first.x, first.y);  // closes it
    assert.equal(await page.locator('#zone-list li').count(), 1);
    // Edit: drag the third corner 5 m east, then save.
    const c = await mapPoint(page, ring[2][0], ring[2][1]);
    const c2 = await mapPoint(page, ring[2][0] + 5, ring[2][1]);
    await page.mouse.move(c.x, c.y);
    await page.mouse.down();
    await page.mouse.move(c2.x, c2.y, { steps: 4 });
    await page.mouse.up();
    await shot(page, 'editing');  // corner handles while the tool is on
    await page.click('#zones-save');
    await page.waitForFunction(() => /saved 1 zone/.test(document.getElementById('zones-status').textContent), null, { timeout: 10000 });
    const saved = await (await fetch(`${server.url}/api/maps/${mapId}/zones`)).json();
    assert.equal(saved.features.length, 1);
    const stored = saved.features[0].geometry.coordinates[0].slice(0, -1);
    assert.equal(stored.length, 4);
    // The drawn corners, within the pixel the click landed on; the dragged one moved ~5 m.
    const px = await page.evaluate(() => 1 / window.__roverplanApp.view.scale);
    for (const k of [0, 1, 3]) {
      assert.ok(Math.hypot(stored[k][0] - ring[k][0], stored[k][1] - ring[k][1]) < 2 * px, `corner ${k}: ${stored[k]}`);
    }
    assert.ok(Math.abs(stored[2][0] - (ring[2][0] + 5)) < 3 * px, `dragged corner: ${stored[2]}`);
    const zone = stored;
    // The legend says what the hatching is.
    assert.match(await page.textContent('#legend-list [data-layer="zones"]'), /no rover enters \(1 zone\)/);
    await page.click('#zones-draw');  // done drawing
    await shot(page, 'drawn');

    // A coverage mission: one rover west of the zone.
    await page.click('#tab-mission');
    assert.equal(await page.isChecked('#m-keep-out'), true, 'on by default when the map has zones');
    await page.selectOption('#m-planner', 'coverage');
    await page.fill('#m-rover-count', '1');
    if ((await page.getAttribute('#m-place', 'aria-pressed')) !== 'true') await page.click('#m-place');
    const s = await mapPoint(page, 30, 75);
    await page.mouse.click(s.x, s.y);
    const cov = await launchAndWait(page, server);
    checkOutside(cov.result, zone, 'coverage');
    assert.ok(cov.result.metrics.keep_out_cells > 100, `keep_out_cells ${cov.result.metrics.keep_out_cells}`);
    await page.waitForTimeout(300);
    await shot(page, 'coverage');

    // Import the zone again from a file in the map's CRS, as an export is written: the coverage
    // run's result.geojson gives the CRS (its "crs" member) and the local -> CRS mapping (its
    // track's points are result.json's path); its LineString is skipped, the Polygon replaces
    // the saved zone.
    const exported = await (await fetch(`${server.url}/api/missions/${cov.id}/result.geojson`)).json();
    const local = cov.result.rovers[0].path, crsLine = exported.features[0].geometry.coordinates;
    const [a, b] = [0, local.length - 1];
    const sx = (crsLine[b][0] - crsLine[a][0]) / (local[b][0] - local[a][0]);
    const sy = (crsLine[b][1] - crsLine[a][1]) / (local[b][1] - local[a][1]);
    const toCrs = ([x, y]) => [crsLine[a][0] + (x - local[a][0]) * sx, crsLine[a][1] + (y - local[a][1]) * sy];
    const inCrs = {
      type: 'FeatureCollection', crs: exported.crs,
      features: [exported.features[0], { type: 'Feature', properties: { name: 'imported' },
        geometry: { type: 'Polygon', coordinates: [[...zone, zone[0]].map(toCrs)] } }],
    };
    await page.click('#tab-maps');
    await page.setInputFiles('#zones-import', { name: 'zones-map-crs.geojson', mimeType: 'application/geo+json', buffer: Buffer.from(JSON.stringify(inCrs)) });
    await page.waitForFunction(() => /imported 1 zone \(map's CRS\), skipped 1 other/.test(document.getElementById('zones-status').textContent), null, { timeout: 10000 });
    const imported = (await (await fetch(`${server.url}/api/maps/${mapId}/zones`)).json()).features;
    assert.equal(imported.length, 1);
    assert.equal(imported[0].properties.name, 'imported');
    imported[0].geometry.coordinates[0].slice(0, -1).forEach(([x, y], k) =>
      assert.ok(Math.hypot(x - zone[k][0], y - zone[k][1]) < 1e-3, `imported corner ${k}: ${x}, ${y} vs ${zone[k]}`));
    await page.click('#tab-mission');

    // A small team mission: two rovers, four targets, west of the zone.
    await page.selectOption('#m-planner', 'team-search');
    await page.fill('#m-rover-count', '2');
    if (await page.locator('#m-param-targets').count()) await page.fill('#m-param-targets', '4');
    if ((await page.getAttribute('#m-place', 'aria-pressed')) !== 'true') await page.click('#m-place');
    for (const [x, y] of [[40, 70], [40, 78]]) {
      const p = await mapPoint(page, x, y);
      await page.mouse.click(p.x, p.y);
    }
    const team = await launchAndWait(page, server);
    checkOutside(team.result, zone, 'team');
    console.log(`team: keep_out_search_cells ${team.result.metrics.keep_out_search_cells}, unreachable_search_cells ${team.result.metrics.unreachable_search_cells}`);
    assert.ok(team.result.metrics.keep_out_search_cells >= 1);
    await page.waitForTimeout(300);
    await shot(page, 'team');
    // The mission file carries the zones, so a re-run keeps out too.
    const file = await (await fetch(`${server.url}/api/missions/${team.id}/mission.json`)).json();
    assert.equal(file.keep_out.features.length, 1);
    assert.deepEqual(errors, []);
    await context.close();
  });

  // Issue 24: zones are OpenLayers features drawn with Draw/Modify/Snap. A corner clicked a few
  // pixels from another zone's corner lands on it exactly (Snap); an edge dragged gets a new
  // corner (Modify); the hatching is on the map's picture inside the zone and not outside it.
  test('a corner near another zone\'s corner snaps onto it, an edge dragged adds a corner, the zone is drawn hatched', async () => {
    const { page, errors, context } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    const mapId = await page.evaluate(() => window.__roverplanApp.state.map.id);
    const zones = () => page.evaluate(() => window.__roverplanApp.zoneEditor.zones.map((z) => z.ring));
    const click = async (x, y, dx = 0, dy = 0) => {
      const p = await mapPoint(page, x, y);
      await page.mouse.click(p.x + dx, p.y + dy);
    };
    // The map may hold the zone the test above saved (x 60–105 m): these are drawn west of it.
    const n0 = (await zones()).length;
    await page.click('#zones-draw');
    const a = [[5, 5], [30, 5], [30, 30], [5, 30]];
    for (const [x, y] of a) await click(x, y);
    await click(a[0][0], a[0][1]);
    const first = (await zones())[n0];
    // The second zone shares the first one's corner (30, 30), clicked 4 px off it. (A press on a
    // corner while no zone is being drawn takes that corner to move it: the shared one comes second.)
    await click(50, 20);
    await click(30, 30, 4, -3);
    await click(50, 40);
    await click(50, 20);  // its first corner: closes it
    const rings = await zones();
    assert.equal(rings.length, n0 + 2, JSON.stringify(rings));
    assert.deepEqual(rings[n0 + 1][1], first[2], `snapped onto the first zone's corner: ${rings[n0 + 1][1]} vs ${first[2]}`);
    assert.equal(rings[n0 + 1].length, 3);
    // Drag the middle of the first zone's south edge 6 m north: a fifth corner there.
    const e0 = await mapPoint(page, 17.5, first[0][1]), e1 = await mapPoint(page, 17.5, first[0][1] + 6);
    await page.mouse.move(e0.x, e0.y);
    await page.mouse.down();
    await page.mouse.move(e1.x, e1.y, { steps: 5 });
    await page.mouse.up();
    const edged = (await zones())[n0];
    assert.equal(edged.length, 5, JSON.stringify(edged));
    const added = edged.find((c) => !first.some((f) => f[0] === c[0] && f[1] === c[1]));
    const px = await page.evaluate(() => 1 / window.__roverplanApp.view.scale);
    assert.ok(Math.abs(added[0] - 17.5) < 3 * px && Math.abs(added[1] - (first[0][1] + 6)) < 3 * px, `added corner ${added}`);
    assert.match(await page.getAttribute('#undo', 'title'), new RegExp(`add a corner to zone ${n0 + 1}`));
    await page.click('#zones-draw');
    // The map's picture (the PNG export's, OL's layers composed): orange hatching inside the first
    // zone, none on the empty ground north of it.
    const colours = await page.evaluate(() => {
      const v = window.__roverplanApp.view;
      const shot = v.snapshot().getContext('2d');
      const orange = (x0, y0) => {
        const [sx, sy] = v.worldToScreen(x0, y0);
        const d = shot.getImageData(Math.round(sx * v.dpr) - 6, Math.round(sy * v.dpr) - 6, 12, 12).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] > 90 && d[i + 1] < 160 && d[i + 2] < 110) n++;
        return n;
      };
      return { inside: orange(17.5, 20), outside: orange(17.5, 50) };
    });
    assert.ok(colours.inside >= 8, `hatch pixels inside the zone: ${colours.inside}`);
    assert.equal(colours.outside, 0, 'no hatching outside');
    await page.click('#zones-save');
    await page.waitForFunction((n) => document.getElementById('zones-status').textContent === `saved ${n} zones`, n0 + 2, { timeout: 10000 });
    const saved = (await (await fetch(`${server.url}/api/maps/${mapId}/zones`)).json()).features;
    assert.deepEqual(saved[n0 + 1].geometry.coordinates[0][1], first[2], 'the shared corner is saved as one point');
    assert.ok(saved[n0].geometry.coordinates[0].some((c) => c[0] === first[2][0] && c[1] === first[2][1]));
    await shot(page, 'snapped');
    assert.deepEqual(errors, []);
    await context.close();
  });
});
