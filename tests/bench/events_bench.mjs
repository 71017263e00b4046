// Event stream figures (issue 26), printed, never asserted:
//   ROVERPLAN_BIN=build/bin/roverplan node --experimental-websocket tests/bench/events_bench.mjs [WRITES] [SUBSCRIBERS]
// A fresh `roverplan serve`; SUBSCRIBERS (default 50) clients on WS /api/events; 4 writers rename
// their own PDM (PUT with the version read) paced to ~100 writes/s in all, WRITES (default 400) in
// all. Printed: the writes' rate, events delivered per second to all subscribers, and the latency
// from a write being sent to its event reaching each subscriber (p50, p99, max), with any gap.
import { startServer } from '../browser/lib/harness.mjs';

const writes = Number(process.argv[2] || 400), subscribers = Number(process.argv[3] || 50), writers = 4;
const server = await startServer();
const base = server.url;
const map = (await (await fetch(`${base}/api/maps`)).json())[0].id;
const pdms = [];
for (let w = 0; w < writers; w++) {
  const r = await fetch(`${base}/api/maps/${map}/pdms`, { method: 'POST', headers: { 'Content-Type': 'application/json' },
    body: JSON.stringify({ name: `w${w}`, components: [{ x: 50, y: 50, sigma_x: 10 }] }) });
  pdms.push((await r.json()).id);
}
const sentAt = new Map();  // "pdm/version" -> ms
const latencies = [];
let gaps = 0, delivered = 0;
const clients = [];
await Promise.all(Array.from({ length: subscribers }, () => new Promise((resolve) => {
  const ws = new WebSocket(`${base.replace('http', 'ws')}/api/events`);
  let last = null;
  ws.onmessage = (m) => {
    const msg = JSON.parse(m.data);
    const now = performance.now();
    if (msg.type === 'ready') { last = msg.seq; resolve(); return; }
    if (msg.type !== 'events') return;
    for (const e of msg.events) {
      if (last !== null && e.seq !== last + 1) gaps++;
      last = e.seq;
      delivered++;
      const t = sentAt.get(`${e.id}/${e.version}`);
      if (t !== undefined) latencies.push(now - t);
    }
  };
  clients.push(ws);
})));
const t0 = performance.now();
await Promise.all(pdms.map(async (id, w) => {
  const each = Math.ceil(writes / writers);
  for (let i = 0; i < each; i++) {
    const due = t0 + (i * writers + w) * 10;  // 100 writes/s in all
    const wait = due - performance.now();
    if (wait > 0) await new Promise((r) => setTimeout(r, wait));
    sentAt.set(`${id}/${i + 2}`, performance.now());
    const r = await fetch(`${base}/api/maps/${map}/pdms/${id}`, { method: 'PUT', headers: { 'Content-Type': 'application/json', 'If-Match': `"v${i + 1}"` },
      body: JSON.stringify({ name: `w${w}-${i}` }) });
    if (r.status !== 200) console.log('write refused', r.status);
  }
}));
const t1 = performance.now();
const expected = Math.ceil(writes / writers) * writers * subscribers;
for (let i = 0; i < 600 && latencies.length < expected; i++) await new Promise((r) => setTimeout(r, 50));
const t2 = performance.now();
latencies.sort((a, b) => a - b);
const q = (p) => latencies[Math.min(latencies.length - 1, Math.floor(p * latencies.length))].toFixed(1);
console.log(`writes: ${writes} in ${((t1 - t0) / 1000).toFixed(2)} s = ${(writes / ((t1 - t0) / 1000)).toFixed(0)}/s from ${writers} writers`);
console.log(`events delivered: ${delivered} to ${subscribers} subscribers (${expected} expected), ` +
  `${(delivered / ((t2 - t0) / 1000)).toFixed(0)}/s, gaps ${gaps}`);
console.log(`write sent -> event received: p50 ${q(0.5)} ms, p99 ${q(0.99)} ms, max ${latencies[latencies.length - 1].toFixed(1)} ms`);
for (const ws of clients) ws.close();
await server.stop();
