// A map whose cells are not square (0.5 m wide, 1 m tall: a GeoTIFF with different x and y pixel
// sizes, made with GDAL here from a checkerboard grid) on the 2D map (issue 24): the OpenLayers view
// is in metres both ways and the tiles cover their true extent, with no CSS stretching. At the
// zoom where a cell is 8 × 16 screen pixels, the cell boundaries the tiles show are where the
// pointer read-out puts them (either side of a colour change the read-out gives the next cell and
// the other height), and a rover's start mark, a disc, is as tall as it is wide (read from
// screenshots, what the operator sees).
import assert from 'node:assert/strict';
import { spawnSync } from 'node:child_process';
import { mkdtempSync, readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, missingPrerequisite, openPage, screenshot, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite() || (spawnSync('gdal_translate', ['--version']).status !== 0 && 'no gdal_translate');
if (missing) console.log(`# browser tests skipped: ${missing}`);

const COLS = 64, ROWS = 48, DX = 0.5, DY = 1;  // metres per cell along x (east) and y (north)
const ROVER = [255, 79, 154];                  // rover 1's colour (util.js ROVER_COLOURS[0])

// A COLS × ROWS GeoTIFF (UTM metres) whose cells alternate 100 m and 120 m, DX × DY metres each:
// an Arc/Info ASCII grid with GDAL's dx/dy header, through gdal_translate.
function checkerboard(dir) {
  const rows = [`ncols ${COLS}`, `nrows ${ROWS}`, 'xllcorner 500000', 'yllcorner 4000000', `dx ${DX}`, `dy ${DY}`];
  for (let r = 0; r < ROWS; r++) rows.push(Array.from({ length: COLS }, (_, c) => ((r + c) % 2 ? 120 : 100)).join(' '));
  const asc = join(dir, 'board.asc'), tif = join(dir, 'board.tif');
  writeFileSync(asc, rows.join('\n') + '\n');
  const r = spawnSync('gdal_translate', ['-q', '-a_srs', 'EPSG:32633', '-ot', 'Float32', asc, tif], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`gdal_translate: ${r.stderr}`);
  return tif;
}

// The screen's pixels in `clip` (page CSS pixels; the device pixel ratio is 1), decoded in the page:
// {w, h, at(x, y) → [r, g, b]}.
async function pixels(page, clip) {
  const png = (await page.screenshot({ clip })).toString('base64');
  const { w, h, data } = await page.evaluate(async (b64) => {
    const img = new Image();
    img.src = `data:image/png;base64,${b64}`;
    await img.decode();
    const c = document.createElement('canvas');
    c.width = img.width;
    c.height = img.height;
    const g = c.getContext('2d');
    g.drawImage(img, 0, 0);
    return { w: c.width, h: c.height, data: Array.from(g.getImageData(0, 0, c.width, c.height).data) };
  }, png);
  return { w, h, at: (x, y) => data.slice(4 * (y * w + x), 4 * (y * w + x) + 3) };
}

const diff = (p, q) => Math.abs(p[0] - q[0]) + Math.abs(p[1] - q[1]) + Math.abs(p[2] - q[2]);
const light = (p) => p[0] + p[1] + p[2];

// Where the colour changes along a line of pixels: the index of each first pixel of a new colour.
function changes(line) {
  const out = [];
  for (let i = 1; i < line.length; i++) if (diff(line[i], line[i - 1]) >= 60) out.push(i);
  return out;
}

// The pointer read-out at page point (x, y): {x, y, elevation} in metres.
async function readout(page, x, y) {
  await page.mouse.move(x, y);
  const text = await page.textContent('#readout');
  const num = (re) => Number((text.match(re) || [])[1]);
  return { x: num(/x (-?[\d.]+) m/), y: num(/y (-?[\d.]+) m/), elevation: num(/elevation (-?[\d.]+) m/), text };
}

describe('a map with non-square cells', { skip: missing || false, timeout: 180000 }, () => {
  let server, browser, work;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
    work = mkdtempSync(join(tmpdir(), 'roverplan-nonsquare-'));
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
    if (work) rmSync(work, { recursive: true, force: true });
  });

  test('tiles cover their cells where the read-out says, and a rover mark stays round', async () => {
    const up = await fetch(`${server.url}/api/maps?name=oblong&filename=board.tif`, {
      method: 'POST', headers: { 'Content-Type': 'image/tiff' }, body: readFileSync(checkerboard(work)),
    });
    assert.equal(up.status, 201, await up.clone().text());
    const map = await up.json();
    assert.equal(map.cols, COLS);
    assert.ok(Math.abs(map.cell_size_m - DX) < 1e-6 && Math.abs(map.cell_height_m - DY) < 1e-6, `cells ${map.cell_size_m} × ${map.cell_height_m} m`);
    const { page, errors, context } = await openPage(browser, `${server.url}/#map=${map.id}`);
    await waitForMap(page);
    await page.waitForFunction((n) => document.getElementById('map-title').textContent.includes(n), 'oblong');
    // The title gives both sides of a cell.
    const title = await page.textContent('#map-title');
    assert.ok(title.includes(`${DX} × ${DY} m`), `the title names both cell sides: ${title}`);
    await page.waitForFunction(() => window.__roverplanApp.layers.rasters.elevation);  // the read-out's heights

    // Zoomed in to 8 px a cell across (16 px/m; the view goes on to 32), centred on a cell corner:
    // x 16 m is a boundary between columns, y 24 m one between rows.
    const view = await page.evaluate(() => {
      const v = window.__roverplanApp.view;
      v.cx = 16;
      v.cy = 24;
      v.scale = 8 / 0.5;
      v.viewChanged();
      const r = v.canvas.getBoundingClientRect();
      return { scale: v.scale, cx: v.cx, cy: v.cy, left: r.left, top: r.top, w: v.cssW, h: v.cssH };
    });
    console.log(`# zoomed in: ${view.scale} px/m, a cell ${view.scale * DX} × ${view.scale * DY} px`);
    assert.equal(view.scale * DX, 8, 'a cell is 8 px wide');
    assert.equal(view.scale * DY, 16, 'and 16 px tall');
    await page.evaluate(() => new Promise((done) => {
      const m = window.__roverplanApp.view.olMap;
      m.once('rendercomplete', done);
      m.render();
    }));

    // A 121-px square of the screen around the view's centre (the corner at 16 m, 24 m).
    const mx = Math.round(view.left + view.w / 2), my = Math.round(view.top + view.h / 2), R = 60;
    const px = await pixels(page, { x: mx - R, y: my - R, width: 2 * R + 1, height: 2 * R + 1 });
    // Along a row through the middle of the cells south of the corner, and a column through the
    // middle of the cells east of it: the colour changes every cell, 8 px across and 16 px down.
    const rowY = R + 8, colX = R + 4;
    const across = changes(Array.from({ length: px.w }, (_, i) => px.at(i, rowY)));
    const down = changes(Array.from({ length: px.h }, (_, j) => px.at(colX, j)));
    const steps = (a) => a.slice(1).map((v, i) => v - a[i]);
    console.log(`# colour changes across ${across.join(' ')} · down ${down.join(' ')}`);
    assert.ok(across.length >= 10 && steps(across).every((d) => Math.abs(d - 8) <= 1), `8 px a cell across: ${across}`);
    assert.ok(down.length >= 5 && steps(down).every((d) => Math.abs(d - 16) <= 1), `16 px a cell down: ${down}`);

    // At each of the changes nearest the centre, the read-out: a pixel before it and one after lie
    // in neighbouring cells (of the other height, the lighter colour the higher cell), and the
    // change itself is on a cell boundary to within a pixel.
    const nearest = (a) => a.reduce((b, v) => (Math.abs(v - R) < Math.abs(b - R) ? v : b));
    const bx = nearest(across), by = nearest(down);
    const pxM = 1 / view.scale;
    for (const [axis, cell, at] of [['x', DX, (k) => [mx - R + bx + k, my - R + rowY]], ['y', DY, (k) => [mx - R + colX, my - R + by + k]]]) {
      const a = await readout(page, ...at(-1)), b = await readout(page, ...at(1)), edge = await readout(page, ...at(0));
      console.log(`# ${axis}: ${a.text} | ${b.text}`);
      const ia = Math.floor(a[axis] / cell), ib = Math.floor(b[axis] / cell);
      assert.equal(Math.abs(ib - ia), 1, `${axis}: the pixels either side of the colour change are in neighbouring cells (${a[axis]}, ${b[axis]})`);
      assert.ok(Math.abs(edge[axis] - Math.round(edge[axis] / cell) * cell) <= pxM + 0.005, `${axis}: the change at ${edge[axis]} m is on a cell boundary`);
      assert.notEqual(a.elevation, b.elevation, `${axis}: the two cells have their own heights`);
      const [pa, pb] = axis === 'x' ? [px.at(bx - 1, rowY), px.at(bx + 1, rowY)] : [px.at(colX, by - 1), px.at(colX, by + 1)];
      assert.equal(a.elevation > b.elevation, light(pa) > light(pb), `${axis}: the higher cell is the lighter one (${pa} vs ${pb})`);
    }

    // A rover placed on the map (the Mission tab places rover 1 on a click): its start mark, a
    // disc 8 px in radius, is as tall as it is wide. Its heading line points east, so the disc is
    // measured west of its centre: half as wide as it is tall.
    await page.click('#tab-mission');
    const rx = mx - 20, ry = my + 30;
    await page.mouse.click(rx, ry);
    await page.waitForFunction(() => window.__roverplanApp.missionForm.rovers[0] !== null);
    await page.evaluate(() => new Promise((done) => {
      const m = window.__roverplanApp.view.olMap;
      m.once('rendercomplete', done);
      m.render();
    }));
    await page.mouse.move(view.left + 5, view.top + view.h - 5);  // the pointer off the mark
    const D = 16;
    const mark = await pixels(page, { x: rx - D, y: ry - D, width: D + 1, height: 2 * D + 1 });
    let x0 = Infinity, x1 = -1, y0 = Infinity, y1 = -1;
    for (let y = 0; y < mark.h; y++) {
      for (let x = 0; x < mark.w; x++) {
        if (diff(mark.at(x, y), ROVER) > 90) continue;
        x0 = Math.min(x0, x);
        x1 = Math.max(x1, x);
        y0 = Math.min(y0, y);
        y1 = Math.max(y1, y);
      }
    }
    const halfWidth = x1 - x0 + 1, height = y1 - y0 + 1;
    console.log(`# rover mark: west half ${halfWidth} px wide, ${height} px tall (rows ${y0}…${y1} of ${mark.h})`);
    assert.ok(height >= 12 && height <= 18, `the disc is about 16 px tall: ${height}`);
    // (the west half holds the centre column: 2 × halfWidth − 1 is the whole width)
    assert.ok(Math.abs(height - (2 * halfWidth - 1)) <= 2, `as tall as wide: ${height} px tall, west half ${halfWidth} px wide`);
    assert.ok(Math.abs((y0 + y1) / 2 - D) <= 1, `centred on the click: rows ${y0}…${y1}`);
    await screenshot(page, 'nonsquare-closest');
    assert.deepEqual(errors, []);
    await context.close();
  });
});
