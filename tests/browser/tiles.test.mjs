// The 2D map on tiles (issue 24): a DEM bigger than the old 1024-px overview, whose adjacent cells
// alternate between two heights (a checkerboard made with GDAL here), zoomed to the closest zoom:
// one cell covers at least 8 screen pixels and two adjacent cells show their own colours (no
// overview blur), while cells two apart show the same colour.
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, missingPrerequisite, openPage, screenshot, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite() || (spawnSync('gdal_translate', ['--version']).status !== 0 && 'no gdal_translate');
if (missing) console.log(`# browser tests skipped: ${missing}`);

const N = 1200;     // cells per side: past the 1024-px overview the page used to show
const CELL = 0.5;   // metres

// An N × N GeoTIFF (UTM metres) whose cells alternate 100 m and 120 m, through GDAL from an
// Arc/Info ASCII grid.
function checkerboard(dir) {
  const rows = [`ncols ${N}`, `nrows ${N}`, 'xllcorner 500000', 'yllcorner 4000000', `cellsize ${CELL}`];
  for (let r = 0; r < N; r++) {
    let line = '';
    for (let c = 0; c < N; c++) line += (r + c) % 2 ? '120 ' : '100 ';
    rows.push(line);
  }
  const asc = join(dir, 'board.asc'), tif = join(dir, 'board.tif');
  writeFileSync(asc, rows.join('\n') + '\n');
  const r = spawnSync('gdal_translate', ['-q', '-a_srs', 'EPSG:32633', '-ot', 'Float32', asc, tif], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`gdal_translate: ${r.stderr}`);
  return tif;
}

describe('map tiles', { skip: missing || false, timeout: 180000 }, () => {
  let server, browser, work;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
    work = mkdtempSync(join(tmpdir(), 'roverplan-tiles-'));
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
    if (work) rmSync(work, { recursive: true, force: true });
  });

  test('at the closest zoom adjacent cells of a checkerboard DEM show their own colours', async () => {
    const up = await fetch(`${server.url}/api/maps?name=checkerboard&filename=board.tif`, {
      method: 'POST', headers: { 'Content-Type': 'image/tiff' }, body: readFileSync(checkerboard(work)),
    });
    assert.equal(up.status, 201, await up.clone().text());
    const map = await up.json();
    assert.equal(map.rows, N);
    assert.ok(map.tiles.zmax >= map.tiles.native_zoom + 2);
    const { page, errors, context } = await openPage(browser, `${server.url}/#map=${map.id}`);
    await waitForMap(page);
    await page.waitForFunction((n) => document.getElementById('map-title').textContent.includes(n), 'checkerboard');

    // Centre on a cell near the middle and zoom in with the + key as far as the page goes (its
    // closest zoom, past the tile grid's finest level), then wait for OpenLayers to have drawn
    // every tile in view.
    const row = Math.floor(N / 2), col = Math.floor(N / 2);
    await page.evaluate(([x, y]) => {
      const v = window.__roverplanApp.view;
      v.cx = x;
      v.cy = y;
      v.viewChanged();
    }, [(col + 0.5) * CELL, (N - row - 0.5) * CELL]);
    await page.focus('#map-canvas');
    let scale = 0;
    for (let i = 0; i < 100; i++) {
      await page.keyboard.press('+');
      const now = await page.evaluate(() => window.__roverplanApp.view.scale);
      if (now === scale) break;
      scale = now;
    }
    await page.evaluate(() => new Promise((done) => {
      const map = window.__roverplanApp.view.olMap;
      map.once('rendercomplete', done);  // fires once every tile in view has loaded and been drawn
      map.render();
    }));

    // Pixels of the composed view (tiles and overlays, as the PNG export takes it) at the centres
    // of a cell, its right neighbour and the cell two to the right.
    const probe = await page.evaluate(([row, col, cell, rows]) => {
      const v = window.__roverplanApp.view;
      const shot = v.snapshot().getContext('2d');
      const px = (rr, cc) => {
        const [sx, sy] = v.worldToScreen((cc + 0.5) * cell, (rows - rr - 0.5) * cell);
        return Array.from(shot.getImageData(Math.round(sx * v.dpr), Math.round(sy * v.dpr), 1, 1).data);
      };
      return { cellPx: v.scale * cell, a: px(row, col), b: px(row, col + 1), c: px(row, col + 2), d: px(row + 1, col + 1) };
    }, [row, col, CELL, N]);
    console.log(`one cell = ${probe.cellPx.toFixed(1)} screen px; colours ${probe.a} | ${probe.b} | ${probe.c}`);
    assert.ok(probe.cellPx >= 8, `one DEM cell covers ${probe.cellPx} screen px`);
    const diff = (p, q) => Math.abs(p[0] - q[0]) + Math.abs(p[1] - q[1]) + Math.abs(p[2] - q[2]);
    assert.equal(probe.a[3], 255, 'the cell is drawn');
    assert.ok(diff(probe.a, probe.b) >= 60, `adjacent cells differ: ${probe.a} vs ${probe.b}`);
    assert.ok(diff(probe.a, probe.c) <= 6, `cells two apart match: ${probe.a} vs ${probe.c}`);
    assert.ok(diff(probe.a, probe.d) <= 6, `the diagonal neighbour matches: ${probe.a} vs ${probe.d}`);
    await screenshot(page, 'tiles-checkerboard-closest');
    assert.deepEqual(errors, []);
    await context.close();
  });
});
