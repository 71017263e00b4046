// The replay slider of a finished mission: step 0..N (a step moves every rover once); play/pause
// runs through the whole mission in about 15 s. The last position shows the final state.

export class Replay {
  constructor({ slider, play, label, seek }) {
    this.slider = slider;
    this.playButton = play;
    this.label = label;
    this.seekTo = seek;
    this.max = 0;
    this.timer = null;
    slider.addEventListener('input', () => {
      this.stop();
      this.apply(Number(slider.value));
    });
    play.addEventListener('click', () => (this.timer ? this.stop() : this.start()));
  }

  enable(max) {
    this.max = Math.max(0, max);
    this.slider.max = String(this.max);
    this.slider.value = String(this.max);
    this.slider.disabled = false;
    this.playButton.disabled = false;
    this.label.textContent = `step ${this.max} / ${this.max} (end)`;
  }

  disable() {
    this.stop();
    this.max = 0;
    this.slider.value = '0';
    this.slider.max = '0';
    this.slider.disabled = true;
    this.playButton.disabled = true;
    this.label.textContent = 'replay after the run';
  }

  apply(step) {
    const end = step >= this.max;
    this.label.textContent = `step ${step} / ${this.max}${end ? ' (end)' : ''}`;
    this.seekTo(step, end);
  }

  start() {
    if (this.slider.disabled) return;
    let step = Number(this.slider.value);
    if (step >= this.max) step = 0;
    const perTick = Math.max(1, Math.round(this.max / (15 * 30)));
    this.playButton.textContent = '❚❚';
    this.playButton.setAttribute('aria-label', 'Pause replay');
    this.timer = setInterval(() => {
      step = Math.min(this.max, step + perTick);
      this.slider.value = String(step);
      this.apply(step);
      if (step >= this.max) this.stop();
    }, 33);
  }

  stop() {
    if (this.timer) clearInterval(this.timer);
    this.timer = null;
    this.playButton.textContent = '▶';
    this.playButton.setAttribute('aria-label', 'Play replay');
  }
}
