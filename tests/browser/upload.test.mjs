// DEM upload: a real DEM (../shared/dems when present, else one made by `roverplan terrain`),
// a PDS3 .IMG + .LBL pair as two parts, drag-and-drop, and a bad upload whose server error the
// page shows in words.
import assert from 'node:assert/strict';
import { existsSync, mkdtempSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import { generatedDem, launchBrowser, missingPrerequisite, openPage, screenshot, sharedDems, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);
const hirise = join(sharedDems, 'mars_gale_hirise_1m/missionDEM.tif');
const ldem = join(sharedDems, 'moon_lola_ldem4_global');

describe('DEM upload', { skip: missing || false, timeout: 240000 }, () => {
  let server, browser, work;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
    work = mkdtempSync(join(tmpdir(), 'roverplan-upload-'));
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
    if (work) rmSync(work, { recursive: true, force: true });
  });

  test('a real DEM uploads with progress and becomes the selected map', async () => {
    let file = hirise, name = 'Gale HiRISE 1 m';
    if (!existsSync(hirise)) {
      console.log(`# ${hirise} is absent (no ../shared/dems): uploading a generated 128×128 DEM instead`);
      file = generatedDem(work, 128);
      name = 'generated 128';
    }
    const { page, errors, context } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    await page.setInputFiles('#dem-files', file);
    await page.fill('#dem-name', name);
    const t0 = Date.now();
    await page.click('#dem-upload');
    await page.waitForFunction((n) => document.getElementById('map-title').textContent.includes(n), name, { timeout: 60000 });
    await page.waitForFunction(() => window.__roverplan.layersLoaded.filter((l) => l === 'elevation').length >= 2);
    console.log(`upload + import + first drawing of ${file.split('/').pop()}: ${Date.now() - t0} ms`);
    assert.equal(await page.locator('#map-list li').count(), 2);
    assert.match(await page.textContent('#map-list li.selected'), new RegExp(name));
    assert.match(await page.textContent('#dem-progress-text'), /added/);
    await page.waitForTimeout(300);
    await screenshot(page, 'upload-real-dem');
    // Select the default map from the list, then back.
    await page.click('#map-list li:first-child button.name');
    await page.waitForFunction(() => /Default/.test(document.getElementById('map-title').textContent));
    await page.click('#map-list li:nth-child(2) button.name');
    await page.waitForFunction((n) => document.getElementById('map-title').textContent.includes(n), name);
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('a PDS3 label and image upload together as two parts', { skip: !existsSync(ldem) && 'no ../shared/dems/moon_lola_ldem4_global' }, async () => {
    const { page, errors, context } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    await page.setInputFiles('#dem-files', [join(ldem, 'LDEM_4.IMG'), join(ldem, 'LDEM_4.LBL')]);
    await page.fill('#dem-name', 'LOLA global');
    await page.click('#dem-upload');
    await page.waitForFunction(() => document.getElementById('map-title').textContent.includes('LOLA global'), null, { timeout: 90000 });
    assert.match(await page.textContent('#map-info'), /1440 × 720/);
    // Delete it again (after confirming): the list shrinks and another map is shown.
    const before = await page.locator('#map-list li').count();
    page.once('dialog', (d) => d.accept());
    await page.click('#map-list li.selected button[aria-label^="delete map"]');
    await page.waitForFunction((n) => document.querySelectorAll('#map-list li').length === n - 1, before);
    await page.waitForFunction(() => !document.getElementById('map-title').textContent.includes('LOLA global'));
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('a bad upload (a text file) shows the server error in the page', async () => {
    const bad = join(work, 'notes.txt');
    writeFileSync(bad, 'this is not a DEM\n');
    const { page, errors, context } = await openPage(browser, `${server.url}/`, { ignore: [/status of 400/] });
    await waitForMap(page);
    // Through drag-and-drop this time.
    await page.evaluate(() => {
      const dt = new DataTransfer();
      dt.items.add(new File(['this is not a DEM\n'], 'notes.txt', { type: 'text/plain' }));
      document.getElementById('drop-zone').dispatchEvent(new DragEvent('drop', { dataTransfer: dt, bubbles: true, cancelable: true }));
    });
    assert.match(await page.textContent('#dem-chosen'), /notes\.txt/);
    await page.click('#dem-upload');
    await page.waitForSelector('#dem-error:not([hidden])');
    const text = await page.textContent('#dem-error');
    console.log(`upload error shown: ${text}`);
    assert.match(text, /not a raster format roverplan reads/);
    assert.match(text, /field: file/);
    // The map stays as it was.
    assert.match(await page.textContent('#map-title'), /Default/);
    await screenshot(page, 'upload-error');
    // The same through the file picker.
    await page.setInputFiles('#dem-files', bad);
    await page.fill('#dem-cell', '-3');
    await page.click('#dem-upload');
    assert.match(await page.textContent('#dem-error'), /cell/);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
