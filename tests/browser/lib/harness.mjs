// Shared by the browser tests: start a roverplan server on a free port with a fresh data
// directory, launch Debian's Chromium through playwright-core, collect console errors, save
// screenshots into tests/browser/artifacts/.
import { spawn, spawnSync } from 'node:child_process';
import { existsSync, mkdirSync, mkdtempSync, rmSync } from 'node:fs';
import { createServer } from 'node:net';
import { tmpdir } from 'node:os';
import { dirname, join, resolve } from 'node:path';
import { fileURLToPath } from 'node:url';
import { after, before, describe } from 'node:test';
import { chromium } from 'playwright-core';

export const browserDir = resolve(dirname(fileURLToPath(import.meta.url)), '..');
export const repoRoot = resolve(browserDir, '../..');
export const artifactsDir = join(browserDir, 'artifacts');
export const roverplanBin = process.env.ROVERPLAN_BIN ? resolve(process.env.ROVERPLAN_BIN) : join(repoRoot, 'build/bin/roverplan');
export const chromiumPath = process.env.CHROMIUM_BIN || '/usr/bin/chromium';
// ROVER_SHARED_DEMS overrides the folder (as for the C++ tests), e.g. from a git worktree.
export const sharedDems = process.env.ROVER_SHARED_DEMS ? resolve(process.env.ROVER_SHARED_DEMS) : resolve(repoRoot, '../shared/dems');

export const CHROMIUM_ARGS = ['--headless', '--no-sandbox', '--disable-gpu', '--disable-background-networking',
  '--disable-component-update', '--disable-sync'];

// Why the suite cannot run here, or null.
export function missingPrerequisite() {
  if (!existsSync(roverplanBin)) return `no roverplan binary at ${roverplanBin} (build it, or set ROVERPLAN_BIN)`;
  if (!existsSync(chromiumPath)) return `no Chromium at ${chromiumPath} (apt-get install -y chromium)`;
  if (!existsSync(join(repoRoot, 'web/node_modules/three/build/three.module.js'))) return 'web/node_modules is missing: run npm ci in web/';
  return null;
}

export function freePort() {
  return new Promise((res, rej) => {
    const s = createServer();
    s.unref();
    s.on('error', rej);
    s.listen(0, '127.0.0.1', () => {
      const { port } = s.address();
      s.close(() => res(port));
    });
  });
}

const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

// Starts `roverplan serve`; resolves once /api/health answers.
export async function startServer({ token = '' } = {}) {
  const dataDir = mkdtempSync(join(tmpdir(), 'roverplan-browser-'));
  let lastError = null;
  for (let attempt = 0; attempt < 3; attempt++) {
    const port = await freePort();
    const args = ['serve', '--port', String(port), '--data', dataDir, '--web', join(repoRoot, 'web'), '--quiet'];
    if (token) args.push('--token', token);
    const proc = spawn(roverplanBin, args, { stdio: ['ignore', 'pipe', 'pipe'] });
    let output = '';
    proc.stdout.on('data', (d) => (output += d));
    proc.stderr.on('data', (d) => (output += d));
    let exited = false;
    proc.on('exit', () => (exited = true));
    const url = `http://127.0.0.1:${port}`;
    const deadline = Date.now() + 60000;
    while (!exited && Date.now() < deadline) {
      try {
        const r = await fetch(`${url}/api/health`);
        if (r.ok) {
          return {
            url, port, dataDir, proc,
            output: () => output,
            async stop() {
              if (!exited) {
                proc.kill('SIGTERM');
                for (let i = 0; i < 100 && !exited; i++) await sleep(50);
                if (!exited) proc.kill('SIGKILL');
              }
              rmSync(dataDir, { recursive: true, force: true });
            },
          };
        }
      } catch { /* not up yet */ }
      await sleep(100);
    }
    if (!exited) proc.kill('SIGKILL');
    lastError = new Error(`roverplan serve did not come up on port ${port}: ${output.slice(-2000)}`);
  }
  rmSync(dataDir, { recursive: true, force: true });
  throw lastError;
}

export async function launchBrowser() {
  return chromium.launch({ executablePath: chromiumPath, args: CHROMIUM_ARGS });
}

// A page that records console errors and page errors; `viewport` defaults to 1280×800.
export async function openPage(browser, url, { viewport = { width: 1280, height: 800 }, ignore = [] } = {}) {
  const context = await browser.newContext({ viewport, acceptDownloads: true });
  const page = await context.newPage();
  const errors = [];
  page.on('console', (m) => {
    if (m.type() !== 'error') return;
    const text = m.text();
    if (ignore.some((re) => re.test(text))) return;
    errors.push(`console.error: ${text}`);
  });
  page.on('pageerror', (e) => errors.push(`page error: ${e.message}`));
  const t0 = Date.now();
  await page.goto(url);
  return { page, context, errors, t0 };
}

export async function screenshot(page, name) {
  mkdirSync(artifactsDir, { recursive: true });
  const path = join(artifactsDir, `${name}.png`);
  await page.screenshot({ path });
  return path;
}

// Waits for the page's first map drawing; returns milliseconds since navigation start.
export async function waitForMap(page, timeout = 30000) {
  await page.waitForFunction(() => window.__roverplan && window.__roverplan.mapDrawn, null, { timeout });
  return page.evaluate(() => window.__roverplan.firstMapDrawMs);
}

// Canvas pixel position of a local-frame point (x east, y north in metres).
export async function mapPoint(page, x, y) {
  return page.evaluate(([x, y]) => {
    const v = window.__roverplanApp.view;
    const [sx, sy] = v.worldToScreen(x, y);
    const r = v.canvas.getBoundingClientRect();
    return { x: r.left + sx, y: r.top + sy };
  }, [x, y]);
}

// A small generated DEM (GeoTIFF) made by the roverplan binary itself.
export function generatedDem(dir, size = 128) {
  const out = join(dir, `terrain-${size}.tif`);
  const r = spawnSync(roverplanBin, ['terrain', '--size', String(size), '--out', out], { encoding: 'utf8' });
  if (r.status !== 0) throw new Error(`roverplan terrain failed: ${r.stderr || r.stdout}`);
  return out;
}

// POSTs JSON to the server; the answer's body, or a thrown Error with the server's error.
export async function postJson(url, body) {
  const r = await fetch(url, { method: 'POST', headers: { 'Content-Type': 'application/json' }, body: JSON.stringify(body) });
  const j = await r.json();
  if (!r.ok) throw new Error(`POST ${url}: ${r.status} ${JSON.stringify(j)}`);
  return j;
}

// Polls a mission until it is no longer queued or running (at most 60 s); its last state.
export async function waitEnded(url, id) {
  for (let i = 0; i < 600; i++) {
    const m = await (await fetch(`${url}/api/missions/${id}`)).json();
    if (!['queued', 'running'].includes(m.status)) return m;
    await sleep(100);
  }
  throw new Error(`mission ${id} did not end within 60 s`);
}

export { sleep };

// A describe() block with its own server and browser, started before its tests and stopped after:
// the tests read ctx.server and ctx.browser. Skipped, with a message, when Chromium or the
// roverplan binary is missing.
export function suiteWithServer(name, { timeout = 180000, serverOptions = {} } = {}, body) {
  const missing = missingPrerequisite();
  if (missing) console.log(`# browser tests skipped (${name}): ${missing}`);
  describe(name, { skip: missing || false, timeout }, () => {
    const ctx = {};
    before(async () => {
      ctx.server = await startServer(serverOptions);
      ctx.browser = await launchBrowser();
    });
    after(async () => {
      await ctx.browser?.close();
      await ctx.server?.stop();
    });
    body(ctx);
  });
}
