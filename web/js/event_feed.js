// The page's one live event stream (WS /api/events, server/streams/event_hub.hpp): every change
// to maps, PDMs, zones, missions and studies of the map shown, and who else has it open. One
// WebSocket per page; a new map reconnects with ?map=, and every reconnect resumes with
// ?since= the last seq received, so no event is missed and none is seen twice (the seq filter
// below drops a repeat, e.g. a batch already applied when the socket closed). When the server no
// longer keeps the events after our seq it says resync_required: the page joins from now and,
// once joined ("ready"), reloads its lists ('resync'), so a change made in between is in the lists
// read or in the events that follow.
//
// Handlers: onEvents([event]) per batch, onReady({seq, connection, presence}), onResync(),
// onStatus('live' | 'reconnecting').

import { eventsUrl } from './api.js';
import { counters } from './state.js';

const RETRY_MS = [250, 500, 1000, 2000, 4000];  // backoff between reconnects, then every 4 s

export class EventFeed {
  constructor(handlers) {
    this.h = handlers;
    this.ws = null;
    this.map = '';
    this.lastSeq = null;   // the last seq received (null: none yet, join from now)
    this.connection = '';  // our presence id (ready.connection)
    this.hello = null;     // {name, map, editing}: said again after every reconnect
    this.failures = 0;
    this.timer = null;
    this.readyOnce = false;
    this.mustReload = false;  // a resync: reload the lists once joined again
    // For the tests: the seqs received, the last 500.
    counters.events = { received: 0, batches: 0, lastSeq: null, resyncs: 0, connects: 0, seqs: [] };
  }

  // Follows `mapId` ('' for none: the events of no map and maps' own).
  open(mapId) {
    this.map = mapId || '';
    this.connect();
  }

  connect() {
    this.close();
    const ws = new WebSocket(eventsUrl(this.map, this.lastSeq));
    this.ws = ws;
    this.readyOnce = false;
    counters.events.connects++;
    ws.onmessage = (e) => {
      if (ws !== this.ws || typeof e.data !== 'string') return;
      let msg;
      try { msg = JSON.parse(e.data); } catch { return; }
      this.message(msg);
    };
    ws.onopen = () => {
      if (ws === this.ws && this.hello) this.sendHello();
    };
    ws.onclose = () => {
      if (ws !== this.ws) return;
      this.ws = null;
      // A since refused before ready (400: ahead of a server that lost its data) is dropped.
      if (!this.readyOnce && ++this.failures >= 2 && this.lastSeq !== null) this.resync();
      this.h.onStatus?.('reconnecting');
      const wait = RETRY_MS[Math.min(this.failures, RETRY_MS.length - 1)];
      this.timer = setTimeout(() => this.connect(), wait);
    };
    ws.onerror = () => { /* onclose follows */ };
  }

  message(msg) {
    if (msg.type === 'events') {
      const fresh = (msg.events || []).filter((e) => this.lastSeq === null || e.seq > this.lastSeq);
      if (!fresh.length) return;
      this.lastSeq = fresh[fresh.length - 1].seq;
      counters.events.received += fresh.length;
      counters.events.batches++;
      counters.events.lastSeq = this.lastSeq;
      counters.events.seqs.push(...fresh.map((e) => e.seq));
      if (counters.events.seqs.length > 500) counters.events.seqs.splice(0, counters.events.seqs.length - 500);
      this.h.onEvents?.(fresh);
    } else if (msg.type === 'ready') {
      this.readyOnce = true;
      this.failures = 0;
      // A join from now: our position is the server's; a resume already moved past every replay.
      if (this.lastSeq === null || msg.seq > this.lastSeq) this.lastSeq = msg.seq;
      counters.events.lastSeq = this.lastSeq;
      this.connection = msg.connection || '';
      this.h.onStatus?.('live');
      this.h.onReady?.(msg);
      if (this.mustReload) {
        this.mustReload = false;
        this.h.onResync?.();
      }
    } else if (msg.type === 'resync_required') {
      this.resync();
    }
  }

  // Our seq is older than what the server keeps: join from now, then reload the lists.
  resync() {
    counters.events.resyncs++;
    this.lastSeq = null;
    this.failures = 0;
    this.mustReload = true;
  }

  // Presence: the operator's name, the map shown and what is being edited ('' for nothing).
  say(hello) {
    this.hello = hello;
    this.sendHello();
  }

  sendHello() {
    if (this.ws && this.ws.readyState === WebSocket.OPEN && this.hello)
      this.ws.send(JSON.stringify({ type: 'hello', ...this.hello }));
  }

  close() {
    clearTimeout(this.timer);
    if (this.ws) {
      const ws = this.ws;
      this.ws = null;
      ws.onmessage = ws.onclose = ws.onerror = ws.onopen = null;
      try { ws.close(); } catch { /* already closed */ }
    }
  }
}
