// The Studies tab (issue 12): a small preset study launched from the page draws its plots (SVG with
// marks) while the progress bar follows the WebSocket; a run of a study on the default map's
// synthetic Mars world opens as a mission, and a grid-world run says why it cannot.
import assert from 'node:assert/strict';
import { copyFileSync, mkdirSync } from 'node:fs';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, missingPrerequisite, openPage, screenshot, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);

// A copy beside the other helpers' screenshots when that folder exists (the lead looks there).
async function shot(page, name) {
  const path = await screenshot(page, name);
  try {
    mkdirSync('/work/wt/shots', { recursive: true });
    copyFileSync(path, `/work/wt/shots/${name}.png`);
  } catch { /* not on the project machine */ }
}

describe('studies', { skip: missing || false, timeout: 240000 }, () => {
  let server, browser;
  before(async () => {
    server = await startServer();
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  test('a preset study launched from the page draws its plots; a run opens as a mission', async () => {
    const { page, errors } = await openPage(browser, `${server.url}/`);
    await waitForMap(page);
    await page.click('#tab-studies');
    await page.waitForSelector('#st-source option[value="laine-fig6"]', { state: 'attached' });
    await page.selectOption('#st-source', 'laine-fig6');
    await page.fill('#st-runs', '4');
    await page.click('#st-launch');
    await page.waitForFunction(() => document.querySelector('#st-status')?.textContent === 'succeeded', null, { timeout: 60000 });
    // The launch line and the list follow the study to its end (issue 27: they read "queued").
    await page.waitForFunction(() => document.querySelector('#st-launch-status')?.textContent === 'succeeded: 16 / 16 runs', null, { timeout: 60000 });
    assert.equal(await page.textContent('#st-list li.selected .badge'), 'succeeded');
    // Its button deletes the ended study (it read "cancel" until the list reloaded).
    assert.equal(await page.textContent('#st-list li.selected button.end'), 'delete');
    // Fig. 6: a line per variant and the band, as SVG paths; the box plot of the chosen metric.
    await page.waitForSelector('figure[data-plot="fig6"] svg [aria-label="line"] path', { state: 'attached' });
    const fig6Lines = await page.locator('figure[data-plot="fig6"] svg [aria-label="line"] path').count();
    assert.equal(fig6Lines, 4, 'one mean line per variant (spiral, spiral+circ, boustrophedon, boustrophedon+circ)');
    assert.ok(await page.locator('figure[data-plot="fig6"] svg [aria-label="area"] path').count() >= 4);
    assert.ok(await page.locator('figure[data-plot="box"] svg [aria-label="bar"] rect, figure[data-plot="box"] svg g[aria-label="bar"] rect').count() >= 4);
    assert.equal(await page.textContent('#st-counters').then((t) => t.split(' ')[0]), '16');
    assert.equal(await page.locator('#st-runs-table tr.run-row').count(), 16);
    await shot(page, 'studies-fig6');

    // Fig. 8: makespan box plots per team size, faceted by grid size (laine-fig8, 1 run each).
    await page.selectOption('#st-source', 'laine-fig8');
    await page.fill('#st-runs', '1');
    await page.click('#st-launch');
    await page.waitForFunction(() => document.querySelector('#study-title')?.textContent.startsWith('laine-fig8')
      && document.querySelector('#st-status')?.textContent === 'succeeded', null, { timeout: 60000 });
    await page.waitForSelector('figure[data-plot="fig8"] svg g[aria-label="bar"] rect', { state: 'attached' });
    assert.equal(await page.locator('figure[data-plot="fig8"] svg g[aria-label="bar"] rect').count(), 18, 'a box per world × team size × variant');
    await shot(page, 'studies-fig8');
    await page.click('#st-list li:nth-child(2) button.name');
    await page.waitForFunction(() => document.querySelector('#study-title')?.textContent.startsWith('laine-fig6'));
    await page.waitForSelector('#st-runs-table tr.run-row[data-run="3"]');

    // A grid-world run cannot be a mission: the page says so.
    await page.click('#st-runs-table tr.run-row[data-run="3"]');
    await page.waitForSelector('#st-run .notice', { state: 'attached' });
    assert.match(await page.textContent('#st-run'), /random obstacle grid/);

    // A grid of the coverage planner on the default map's world: its runs open as missions.
    await page.selectOption('#st-source', 'grid');
    await page.selectOption('#st-planner', 'coverage');
    await page.selectOption('#st-world', 'mars');
    await page.fill('#st-name', 'patterns on mars');
    await page.fill('#st-params input[data-key="pattern"]', 'spiral, boustrophedon');
    await page.fill('#st-params input[data-key="coverage"]', '0.3');
    await page.fill('#st-runs', '2');
    await page.click('#st-launch');
    await page.waitForFunction(() => document.querySelector('#study-title')?.textContent.startsWith('patterns on mars')
      && document.querySelector('#st-status')?.textContent === 'succeeded', null, { timeout: 60000 });
    await page.waitForSelector('figure[data-plot="box"] svg g[aria-label="bar"] rect', { state: 'attached' });
    await page.click('#st-runs-table tr.run-row[data-run="1"]');
    await page.waitForSelector('#st-open-mission');
    await shot(page, 'studies-run');
    await page.click('#st-open-mission');
    // The Runs tab shows the new mission live, then ended, with the run's metrics.
    await page.waitForFunction(() => !document.querySelector('#panel-runs').hidden && /succeeded/.test(document.querySelector('#live-status')?.textContent || ''), null, { timeout: 60000 });
    const missions = await (await fetch(`${server.url}/api/missions`)).json();
    assert.equal(missions.length, 1);
    assert.match(missions[0].label, /patterns on mars · pattern=spiral · run 1/);
    const runs = await (await fetch(`${server.url}/api/studies`)).json();
    const csv = await (await fetch(`${server.url}/api/studies/${runs[0].id}/runs.csv`)).text();
    const head = csv.split('\n')[0].split(','), row = csv.split('\n')[2].split(',');
    assert.equal(Number(row[head.indexOf('moves')]), missions[0].metrics.moves, 'the mission replays the run: same moves');
    await shot(page, 'studies-mission');
    assert.deepEqual(errors, []);
  });

  test('a study renamed on the page; a rename from a stale version offers keep mine / take theirs', async () => {
    // The 412 below is answered on purpose (Chromium logs it as a failed load).
    const { page, errors } = await openPage(browser, `${server.url}/`, { ignore: [/status of 412/] });
    await waitForMap(page);
    await page.click('#tab-studies');
    const [study] = await (await fetch(`${server.url}/api/studies`)).json();
    const row = page.locator(`#st-list li[data-study="${study.id}"]`);
    await row.locator('button.rename').click();
    await row.locator('input.rename').fill('mars patterns');
    await row.locator('input.rename').press('Enter');
    await page.waitForFunction(() => document.querySelector('#study-title')?.textContent.startsWith('mars patterns ·'), null, { timeout: 20000 });
    // Another operator renames it while this page's rename is open: the title follows the event
    // stream, and this page's save is refused with theirs shown.
    await row.locator('button.rename').click();
    const r = await fetch(`${server.url}/api/studies/${study.id}`, { method: 'PATCH', headers: { 'Content-Type': 'application/json', 'If-Match': `"v${study.version + 1}"` }, body: JSON.stringify({ name: 'theirs' }) });
    assert.equal(r.status, 200);
    await page.waitForFunction(() => document.querySelector('#study-title')?.textContent.startsWith('theirs ·'), null, { timeout: 20000 });
    await row.locator('input.rename').fill('mine');
    await row.locator('input.rename').press('Enter');
    const box = row.locator('.name-conflict');
    await box.waitFor({ timeout: 20000 });
    assert.match(await box.textContent(), /renamed this study to “theirs”.*yours: “mine”/);
    await box.locator('button.take-theirs').click();
    await page.waitForFunction((id) => document.querySelector(`#st-list li[data-study="${id}"] button.name`)?.textContent.startsWith('theirs ·'), study.id, { timeout: 20000 });
    const stored = await (await fetch(`${server.url}/api/studies/${study.id}`)).json();
    assert.equal(stored.name, 'theirs');
    assert.equal(stored.version, study.version + 2);
    assert.deepEqual(errors, []);
  });
  test('a study stream dropped before the study ends is opened again: the page reads the end', async () => {
    const { page, errors } = await openPage(browser, `${server.url}/`);
    // The first stream of the study launched below closes at once, without a frame (a dropped
    // connection); the later ones reach the server.
    let dropped = null, blockerId = null;
    await page.routeWebSocket(/\/api\/studies\/[0-9a-f]+\/stream/, (ws) => {
      if (!dropped && blockerId && !ws.url().includes(blockerId)) {
        dropped = ws.url();
        ws.close({ code: 1011, reason: 'dropped by the test' });
        return;
      }
      ws.connectToServer();
    });
    await waitForMap(page);
    // A long study first: the one launched from the page waits queued behind it (one study runs
    // at a time), so the page cannot have read its end before its stream is dropped.
    const post = await fetch(`${server.url}/api/studies`, { method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ preset: 'laine-fig6', runs: 1000 }) });
    assert.equal(post.status, 202);
    blockerId = (await post.json()).id;
    await page.click('#tab-studies');
    await page.waitForSelector('#st-source option[value="laine-fig6"]', { state: 'attached' });
    await page.selectOption('#st-source', 'laine-fig6');
    await page.fill('#st-runs', '1');
    await page.click('#st-launch');
    await page.waitForFunction(() => /^queued: 4 runs|^queued: 0 \/ 4/.test(document.querySelector('#st-launch-status')?.textContent || ''), null, { timeout: 60000 });
    const launched = (await (await fetch(`${server.url}/api/studies`)).json()).find((s) => s.id !== blockerId);
    await page.waitForFunction((id) => document.querySelector('#study-title')?.textContent.endsWith(id), launched.id, { timeout: 60000 });
    assert.ok(dropped?.includes(launched.id), `the launched study's first stream was dropped (${dropped})`);
    assert.equal(await page.textContent('#st-status'), 'queued');
    // The blocker cancelled: the launched study runs, and the page follows it to its end.
    assert.equal((await fetch(`${server.url}/api/studies/${blockerId}`, { method: 'DELETE' })).status, 202);
    await page.waitForFunction(() => document.querySelector('#st-status')?.textContent === 'succeeded', null, { timeout: 60000 });
    await page.waitForFunction(() => document.querySelector('#st-launch-status')?.textContent === 'succeeded: 4 / 4 runs', null, { timeout: 60000 });
    assert.deepEqual(errors, []);
  });
});
