// Page sync figures (issue 26), printed, never asserted:
//   ROVERPLAN_BIN=build/bin/roverplan node tests/bench/page_sync_bench.mjs [SAVES] [PAGES]
// A fresh `roverplan serve` and PAGES (default 2) pages in Chromium, each its own browser context
// (another operator), on the default map. SAVES (default 30) PDMs are saved through the API one
// after another; for each, the time from the POST being sent to the PDM showing in every page's
// PDM list and mission form's PDM menu (the event, the list read again, both redrawn) is timed.
// Printed: p50, p99 and max over SAVES × PAGES, and the number of events each page received.
import { launchBrowser, openPage, startServer, waitForMap } from '../browser/lib/harness.mjs';

const saves = Number(process.argv[2] || 30), pages = Number(process.argv[3] || 2);
const server = await startServer();
const browser = await launchBrowser();
try {
  const open = [];
  for (let i = 0; i < pages; i++) {
    const o = await openPage(browser, `${server.url}/`);
    await waitForMap(o.page);
    await o.page.waitForFunction(() => window.__roverplan.events?.lastSeq !== null);
    open.push(o);
  }
  const map = await open[0].page.evaluate(() => window.__roverplanApp.state.map.id);
  const latencies = [];
  for (let i = 0; i < saves; i++) {
    const name = `bench ${i}`;
    const t0 = performance.now();
    const shown = open.map(({ page }) => page.waitForFunction((n) =>
      [...document.querySelectorAll('#m-pdm option')].some((o) => o.textContent === n) &&
      [...document.querySelectorAll('#pdm-list button.name')].some((b) => b.textContent === n), name, { timeout: 30000, polling: 'raf' })
      .then(() => latencies.push(performance.now() - t0)));
    const r = await fetch(`${server.url}/api/maps/${map}/pdms`, { method: 'POST', headers: { 'Content-Type': 'application/json' },
      body: JSON.stringify({ name, components: [{ x: 20 + i, y: 50, sigma_x: 10 }] }) });
    if (r.status !== 201) throw new Error(`save ${i}: ${r.status} ${await r.text()}`);
    await Promise.all(shown);
  }
  latencies.sort((a, b) => a - b);
  const q = (p) => latencies[Math.min(latencies.length - 1, Math.floor(p * latencies.length))].toFixed(1);
  const received = await Promise.all(open.map(({ page }) => page.evaluate(() => window.__roverplan.events.received)));
  console.log(`PDM saved (API) -> in the PDM list and the mission form of ${pages} pages, ${saves} saves: ` +
    `p50 ${q(0.5)} ms, p99 ${q(0.99)} ms, max ${latencies[latencies.length - 1].toFixed(1)} ms; events received per page: ${received.join(', ')}`);
} finally {
  await browser.close();
  await server.stop();
}
