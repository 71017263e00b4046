// The Runs tab (issue 13): each run shows its label, map name, PDM name and key metrics; a run is
// renamed in place (PATCH) and an ended one deleted with its results.
import assert from 'node:assert/strict';
import { readFileSync, rmSync, writeFileSync } from 'node:fs';
import { tmpdir } from 'node:os';
import { join } from 'node:path';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, missingPrerequisite, openPage, postJson, screenshot, startServer, waitEnded, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);

describe('runs', { skip: missing || false, timeout: 240000 }, () => {
  let server, browser;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  test('runs show label, map, PDM and metrics; rename and delete from the list', async () => {
    const map = (await (await fetch(`${server.url}/api/maps`)).json())[0];
    const pdm = await postJson(`${server.url}/api/maps/${map.id}/pdms`, { name: 'two spots', random: 2, seed: 5 });
    const a = await postJson(`${server.url}/api/missions`, {
      map: map.id, planner: 'coverage', name: 'north strip', pace: 0, rovers: [{ x: 30, y: 40, heading: 0 }], params: { coverage: 0.2 },
    });
    const b = await postJson(`${server.url}/api/missions`, {
      map: map.id, pdm: pdm.id, planner: 'coverage', pace: 0, rovers: [{ x: 100, y: 100, heading: 0 }], params: { coverage: 0.2 },
    });
    await waitEnded(server.url, a.id);
    await waitEnded(server.url, b.id);

    const { page, errors, context } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    await page.click('#tab-runs');
    await page.waitForSelector(`#run-list li[data-mission="${b.id}"]`);
    const rowA = page.locator(`#run-list li[data-mission="${a.id}"]`);
    const rowB = page.locator(`#run-list li[data-mission="${b.id}"]`);
    assert.equal(await rowA.locator('button.name').textContent(), 'north strip');
    assert.match(await rowA.locator('.run-where').textContent(), new RegExp(`^${map.name.slice(0, 20).replace(/[()]/g, '.')}`));
    assert.match(await rowB.locator('.run-where').textContent(), /PDM two spots/);
    assert.match(await rowA.locator('.run-metrics').textContent(), /^\d+\.\d % · [\d,]+ moves/);

    // Rename B in place: Enter saves it on the server.
    await rowB.locator('button[aria-label^="rename"]').click();
    await page.fill(`input[aria-label="label of run ${b.id}"]`, 'south crater rim');
    await page.press(`input[aria-label="label of run ${b.id}"]`, 'Enter');
    await page.waitForFunction((id) => document.querySelector(`#run-list li[data-mission="${id}"] button.name`)?.textContent === 'south crater rim', b.id);
    assert.equal((await (await fetch(`${server.url}/api/missions/${b.id}`)).json()).label, 'south crater rim');
    await screenshot(page, 'runs-list');

    // Delete A (the page asks first).
    page.once('dialog', (d) => d.accept());
    await rowA.locator('button[aria-label^="delete"]').click();
    await page.waitForFunction((id) => !document.querySelector(`#run-list li[data-mission="${id}"]`), a.id);
    assert.equal((await fetch(`${server.url}/api/missions/${a.id}`)).status, 404);
    assert.equal(await page.locator('#run-list li').count(), 1);
    assert.deepEqual(errors, []);
    await context.close();
  });

  test('a mission file round trip, and duplicate and edit, give the same result', async () => {
    const map = (await (await fetch(`${server.url}/api/maps`)).json())[0];
    const a = await postJson(`${server.url}/api/missions`, {
      map: map.id, planner: 'coverage', name: 'seeded strip', pace: 0, rovers: [{ x: 40.25, y: 60.5, heading: 30 }],
      params: { coverage: 0.25, pattern: 'boustrophedon' },
    });
    await waitEnded(server.url, a.id);
    const resultOf = async (id) => {
      const r = await (await fetch(`${server.url}/api/missions/${id}/result.json`)).json();
      return { rovers: r.rovers, metrics: r.metrics };
    };
    const original = await resultOf(a.id);

    const { page, errors, context } = await openPage(browser, `${server.url}/`, { ignore: [/status of 409/] });
    await waitForMap(page);
    await page.click('#tab-runs');
    const row = page.locator(`#run-list li[data-mission="${a.id}"]`);
    await row.waitFor();
    // The run's mission file, downloaded from its row, then opened in the Mission tab.
    const [download] = await Promise.all([page.waitForEvent('download'), row.locator('button[aria-label^="mission file"]').click()]);
    const path = await download.path();
    const file = JSON.parse(readFileSync(path, 'utf8'));
    assert.equal(file.format, 'roverplan-mission');
    assert.equal(file.dem_sha256.length, 64);
    await page.click('#tab-mission');
    await page.setInputFiles('#m-file', path);
    await page.waitForFunction((id) => window.__roverplan.missionId && window.__roverplan.missionId !== id, a.id, { timeout: 30000 });
    const fromFile = await page.evaluate(() => window.__roverplan.missionId);
    await waitEnded(server.url, fromFile);
    assert.deepEqual(await resultOf(fromFile), original);

    // Duplicate and edit: the form holds the run; launched unchanged, the same result again.
    await page.click('#tab-runs');
    await page.locator(`#run-list li[data-mission="${a.id}"] button[aria-label^="duplicate"]`).click();
    await page.waitForFunction(() => !document.getElementById('panel-mission').hidden);
    assert.equal(await page.inputValue('#m-planner'), 'coverage');
    assert.equal(await page.inputValue('#m-param-coverage'), '0.25');
    assert.equal(await page.inputValue('#m-param-pattern'), 'boustrophedon');
    assert.equal(await page.inputValue('#m-name'), 'seeded strip (copy)');
    assert.deepEqual(await page.evaluate(() => window.__roverplanApp.missionForm.rovers), [{ x: 40.25, y: 60.5, heading: 30 }]);
    await screenshot(page, 'runs-duplicate');
    await page.click('#m-launch');
    await page.waitForFunction((id) => window.__roverplan.missionId && window.__roverplan.missionId !== id, fromFile, { timeout: 30000 });
    const copy = await page.evaluate(() => window.__roverplan.missionId);
    await waitEnded(server.url, copy);
    assert.deepEqual(await resultOf(copy), original);
    assert.equal((await (await fetch(`${server.url}/api/missions/${copy}`)).json()).label, 'seeded strip (copy)');

    // A file for other ground is refused in words, naming the field.
    const tampered = join(tmpdir(), `roverplan-mission-${process.pid}.json`);
    writeFileSync(tampered, JSON.stringify({ ...file, dem_sha256: '0'.repeat(64) }));
    await page.click('#tab-mission');
    await page.setInputFiles('#m-file', tampered);
    await page.waitForFunction(() => /dem_sha256/.test(document.getElementById('m-error').textContent));
    rmSync(tampered);
    assert.deepEqual(errors, []);
    await context.close();
  });
});
