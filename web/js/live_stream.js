// The mission WebSocket (server/missions/mission_stream.hpp): a JSON snapshot, binary grid
// frames (type 2 full, type 1 diff), JSON poses / progress / status / overlay, and a final JSON "done"
// before a normal close. This module only speaks the protocol and counts frames; what to do with
// them is up to the handlers (mission_view.js).

import { streamUrl } from './api.js';
import { counters } from './state.js';

export class LiveStream {
  // handlers: {snapshot(msg), grid(buffer), poses(msg), progress(msg), status(msg), overlay(msg), done(msg), closed(info)}
  constructor(handlers) {
    this.handlers = handlers;
    this.ws = null;
    this.missionId = null;
    this.done = false;
  }

  open(missionId) {
    this.close();
    this.missionId = missionId;
    this.done = false;
    const ws = new WebSocket(streamUrl(missionId));
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    const h = this.handlers;
    ws.onmessage = (e) => {
      if (ws !== this.ws) return;
      counters.wsMessages++;
      if (typeof e.data !== 'string') {
        counters.gridFrames++;
        const type = h.grid ? h.grid(e.data) : 0;
        if (type === 2) counters.fullGridFrames++;
        else if (type === 1) counters.diffGridFrames++;
        return;
      }
      let msg;
      try {
        msg = JSON.parse(e.data);
      } catch {
        console.warn('stream: a text frame that is not JSON');
        return;
      }
      switch (msg.type) {
        case 'snapshot': h.snapshot && h.snapshot(msg); break;
        case 'poses': counters.posesFrames++; h.poses && h.poses(msg); break;
        case 'progress': counters.progressFrames++; h.progress && h.progress(msg); break;
        case 'status': h.status && h.status(msg); break;
        case 'overlay': counters.overlayFrames = (counters.overlayFrames || 0) + 1; h.overlay && h.overlay(msg); break;
        case 'incidents': counters.incidentFrames = (counters.incidentFrames || 0) + 1; h.incidents && h.incidents(msg); break;
        case 'done':
          counters.doneFrames++;
          this.done = true;
          h.done && h.done(msg);
          break;
        default: break;
      }
    };
    ws.onclose = (e) => {
      if (ws !== this.ws) return;
      this.ws = null;
      h.closed && h.closed({ code: e.code, reason: e.reason, done: this.done });
    };
    ws.onerror = () => { /* onclose follows and reports */ };
  }

  get live() {
    return Boolean(this.ws) && !this.done;
  }

  close() {
    if (this.ws) {
      const ws = this.ws;
      this.ws = null;
      ws.onmessage = ws.onclose = ws.onerror = null;
      try { ws.close(); } catch { /* already closed */ }
    }
  }
}
