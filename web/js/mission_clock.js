// The replay clock of a finished mission: a scrubber, play/pause and a play speed, with the
// incidents as marks on a strip above the scrubber. A team mission replays in mission time
// (seconds; 1× is real time, so its 27 minutes take 27 s at 60×); a coverage run has no clock
// and replays in steps (a step moves every rover once), its speeds in steps per second.
// The last position shows the final state.

const TIME_SPEEDS = [1, 10, 60, 600];
const STEP_SPEEDS = [10, 30, 100, 300, 1000];

// 1234.5 s → "20:34.5" (min:s), 4000 s → "1:06:40".
export function clockText(s) {
  const t = Math.max(0, s);
  const h = Math.floor(t / 3600), m = Math.floor((t % 3600) / 60), sec = t % 60;
  const ss = sec.toFixed(t < 600 ? 1 : 0).padStart(t < 600 ? 4 : 2, '0');
  return h ? `${h}:${String(m).padStart(2, '0')}:${ss}` : `${m}:${ss}`;
}

export class MissionClock {
  // onSeek(t, end): show the mission at t (s or step); end = the final state.
  // marks(): [{at, colour}] drawn on the strip; onMark(i): a mark was clicked.
  constructor({ slider, play, speed, label, strip, onSeek, marks = () => [], onMark = () => {} }) {
    this.slider = slider;
    this.playButton = play;
    this.speedSelect = speed;
    this.label = label;
    this.strip = strip;
    this.onSeek = onSeek;
    this.marks = marks;
    this.onMark = onMark;
    this.unit = 'step';
    this.end = 0;
    this.time = 0;
    this.raf = 0;
    slider.addEventListener('input', () => {
      this.pause();
      this.seek(Number(slider.value));
    });
    play.addEventListener('click', () => (this.raf ? this.pause() : this.play()));
    speed.addEventListener('change', () => this.showLabel());
    strip.addEventListener('click', (e) => this.clickStrip(e));
    new ResizeObserver(() => this.drawStrip()).observe(strip);
    this.disable();
  }

  get playing() {
    return this.raf !== 0;
  }

  get speed() {
    return Number(this.speedSelect.value) || 1;
  }

  setSpeed(v) {
    this.speedSelect.value = String(v);
    this.showLabel();
  }

  // unit 's': end in seconds of mission time; 'step': end in steps.
  enable(end, unit = 'step') {
    this.pause();
    this.unit = unit;
    this.end = Math.max(0, end);
    const speeds = unit === 's' ? TIME_SPEEDS : STEP_SPEEDS;
    // Default: the whole mission in 15–45 s of watching.
    const fit = speeds.find((v) => this.end / v <= 45) ?? speeds[speeds.length - 1];
    this.speedSelect.replaceChildren(...speeds.map((v) => {
      const o = document.createElement('option');
      o.value = String(v);
      o.textContent = unit === 's' ? `${v}×` : `${v} steps/s`;
      return o;
    }));
    this.speedSelect.value = String(fit);
    this.speedSelect.title = unit === 's' ? 'Play speed: mission seconds per second' : 'Play speed: steps per second';
    this.slider.max = String(this.end);
    this.slider.step = unit === 's' ? '0.1' : '1';
    this.slider.setAttribute('aria-label', unit === 's' ? 'Replay time (s of mission time)' : 'Replay time (step)');
    for (const n of [this.slider, this.playButton, this.speedSelect]) n.disabled = false;
    this.time = this.end;
    this.slider.value = String(this.end);
    this.showLabel();
    this.drawStrip();
  }

  disable() {
    this.pause();
    this.end = 0;
    this.time = 0;
    this.slider.value = '0';
    this.slider.max = '0';
    for (const n of [this.slider, this.playButton, this.speedSelect]) n.disabled = true;
    this.label.textContent = 'replay after the run';
    this.drawStrip();
  }

  // Show the mission at t (clamped); keeps playing if it was.
  seek(t) {
    this.time = Math.max(0, Math.min(this.end, this.unit === 'step' ? Math.round(t) : t));
    this.slider.value = String(this.time);
    this.showLabel();
    this.onSeek(this.time, this.time >= this.end);
  }

  showLabel() {
    if (this.slider.disabled) return;
    const end = this.time >= this.end ? ' (end)' : '';
    this.label.textContent = this.unit === 's'
      ? `${clockText(this.time)} / ${clockText(this.end)}${end}`
      : `step ${this.time} / ${this.end}${end}`;
    this.label.title = this.unit === 's' ? `mission time ${this.time.toFixed(1)} s of ${this.end.toFixed(1)} s` : '';
  }

  play() {
    if (this.slider.disabled) return;
    if (this.time >= this.end) this.seek(0);
    this.playButton.textContent = '❚❚';
    this.playButton.setAttribute('aria-label', 'Pause replay');
    let last = performance.now();
    const tick = (now) => {
      // Whole steps in step mode: the fraction carries over to the next frame.
      this.carry = (this.carry || 0) + ((now - last) / 1000) * this.speed;
      last = now;
      const advance = this.unit === 'step' ? Math.floor(this.carry) : this.carry;
      this.carry -= advance;
      if (advance > 0) this.seek(this.time + advance);
      if (this.time >= this.end) return this.pause();
      this.raf = requestAnimationFrame(tick);
    };
    this.raf = requestAnimationFrame(tick);
  }

  pause() {
    if (this.raf) cancelAnimationFrame(this.raf);
    this.raf = 0;
    this.carry = 0;
    this.playButton.textContent = '▶';
    this.playButton.setAttribute('aria-label', 'Play replay');
  }

  // --- the incident strip: one tick per mark, at the scrubber's x of its time ---
  // The range input's thumb centre runs from half a thumb in from each end.
  stripX(t, w) {
    const inset = 8;
    return inset + (this.end > 0 ? t / this.end : 0) * (w - 2 * inset);
  }

  drawStrip() {
    const c = this.strip;
    const r = c.getBoundingClientRect();
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(r.width)), h = Math.max(1, Math.round(r.height));
    if (c.width !== Math.round(w * dpr) || c.height !== Math.round(h * dpr)) {
      c.width = Math.round(w * dpr);
      c.height = Math.round(h * dpr);
    }
    const ctx = c.getContext('2d');
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, w, h);
    if (this.slider.disabled) return;
    const marks = this.marks();
    for (const m of marks) {
      const x = Math.round(this.stripX(m.at, w)) + 0.5;
      ctx.strokeStyle = m.colour;
      ctx.lineWidth = m.selected ? 3 : 1;
      ctx.beginPath();
      ctx.moveTo(x, m.selected ? 0 : 2);
      ctx.lineTo(x, h);
      ctx.stroke();
    }
  }

  clickStrip(e) {
    if (this.slider.disabled) return;
    const r = this.strip.getBoundingClientRect();
    const x = e.clientX - r.left;
    let best = -1, bestD = 6;  // px
    this.marks().forEach((m, i) => {
      const d = Math.abs(this.stripX(m.at, r.width) - x);
      if (d < bestD) (best = i), (bestD = d);
    });
    if (best >= 0) this.onMark(best);
    else this.seek(((x - 8) / Math.max(1, r.width - 16)) * this.end);
  }
}
