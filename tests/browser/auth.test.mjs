// A server started with --token: the page asks for the token, keeps it in localStorage, sends it
// as a bearer header (and ?token= on the WebSocket).
import assert from 'node:assert/strict';
import { after, before, describe, test } from 'node:test';
import { launchBrowser, missingPrerequisite, openPage, startServer, waitForMap } from './lib/harness.mjs';

const missing = missingPrerequisite();
if (missing) console.log(`# browser tests skipped: ${missing}`);
const TOKEN = 'sesame-4711';

describe('bearer token', { skip: missing || false, timeout: 180000 }, () => {
  let server, browser;
  before(async () => {
    server = await startServer({ token: TOKEN });
    browser = await launchBrowser();
  });
  after(async () => {
    await browser?.close();
    await server?.stop();
  });

  test('the page works behind --token once the token is entered', async () => {
    const { page, errors, context } = await openPage(browser, `${server.url}/`, { ignore: [/status of 401/] });
    await page.waitForFunction(() => /token/.test(document.getElementById('status-line').textContent));
    await page.fill('#token', TOKEN);
    await page.dispatchEvent('#token', 'change');
    await waitForMap(page);
    assert.equal(await page.evaluate(() => localStorage.getItem('roverplan.token')), TOKEN);
    // A reload keeps it; a short mission streams through ?token=.
    await page.reload();
    await waitForMap(page);
    await page.evaluate(() => {
      const f = window.__roverplanApp.missionForm;
      f.rovers = [{ x: 20, y: 20, heading: 0 }, { x: 60, y: 60, heading: 0 }];
      f.renderRovers();
    });
    await page.click('#tab-mission');
    await page.fill('#m-param-coverage', '0.05');
    await page.fill('#m-pace', '0');
    await page.click('#m-launch');
    await page.waitForFunction(() => window.__roverplan.doneFrames > 0, null, { timeout: 60000 });
    assert.equal(await page.evaluate(() => window.__roverplan.missionStatus), 'succeeded');
    assert.ok(await page.evaluate(() => window.__roverplan.gridFrames) > 0);
    // Exports go through fetch with the header.
    await page.waitForSelector('#export-csv:not(.disabled)');
    const [download] = await Promise.all([page.waitForEvent('download'), page.click('#export-csv')]);
    assert.match(download.suggestedFilename(), /result\.csv$/);
    assert.deepEqual(errors.filter((e) => !/401/.test(e)), []);
    await context.close();
  });
});
