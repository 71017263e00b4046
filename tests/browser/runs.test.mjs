// The Runs tab (issue 13): each run shows its label, map name, PDM name and key metrics; a run is
// renamed in place (PATCH) and an ended one deleted with its results.
import assert from 'node:assert/strict';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, missingPrerequisite, openPage, screenshot, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);

async function postJson(url, body) {
  const r = await fetch(url, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
  const j = await r.json();
  assert.ok(r.ok, JSON.stringify(j));
  return j;
}

async function waitEnded(url, id) {
  for (let i = 0; i < 600; i++) {
    const m = await (await fetch(`${url}/api/missions/${id}`)).json();
    if (!['queued', 'running'].includes(m.status)) return m;
    await new Promise((r) => setTimeout(r, 100));
  }
  throw new Error(`mission ${id} did not end`);
}

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
});
