// Real time, honestly: each animation frame runs the steps the wall time since the last one
// asks for, within a compute budget. What a frame cannot run carries over, but never more
// than one frame's worth: the rest is dropped and counted, so after a stall (a hidden tab, a
// long task) the page goes on in real time instead of racing to catch up, and when it cannot
// keep up it plays in slow motion and says so. The cost and the real-time ratio are over the
// last second, so switching an effect shows its price within a second.

// Largest compute per animation frame, ms: past it the page lags rather than freezes. Where
// frames come slower (a software rasteriser), up to 60 % of the time between them, to 150 ms.
export const FRAME_BUDGET_MS = 40;
const SLOW_FRAME_BUDGET_MS = 150;
// The window the cost and the ratio are measured over, ms.
const WINDOW_MS = 1000;
// Frames whose intervals make the typical frame (their median).
const TYPICAL_OF = 15;

export class Clock {
  // `now()` gives the page's time in ms; tests move it forward through `skip`.
  constructor(now = () => performance.now()) {
    this.source = now;
    this.skipped = 0;
    this.restart();
  }

  now() {
    return this.source() + this.skipped;
  }

  // Moves the page's time forward by `ms` at once: what the next frame sees is what it sees
  // after the main thread was blocked that long (the test of a stall, without waiting).
  skip(ms) {
    this.skipped += ms;
  }

  restart() {
    this.last = this.now();
    this.started = this.last;
    this.owed = 0; // steps due and not yet run (at most one frame's worth)
    this.frameMs = 16.7; // a typical frame, ms: the median of the last intervals
    this.intervals = [];
    this.droppedSteps = 0;
    this.steps = 0;
    this.history = []; // [time, wall ms, steps run, compute ms]
    this.paused = false;
  }

  // One animation frame: runs `step(n)` for the steps due (in batches, within the budget)
  // with `dt` seconds per step. Returns the steps run.
  advance(dt, step) {
    const now = this.now();
    const wall = now - this.last;
    this.last = now;
    if (this.paused) return 0;
    // A frame makes up at most twice a typical frame (and 100 ms at least): the rest of a
    // longer one is a stall, dropped at once.
    const frame = Math.min(wall, Math.max(100, 2 * this.frameMs));
    this.droppedSteps += Math.floor((wall - frame) / 1000 / dt);
    this.intervals.push(frame);
    if (this.intervals.length > TYPICAL_OF) this.intervals.shift();
    this.frameMs = [...this.intervals].sort((a, b) => a - b)[Math.floor(this.intervals.length / 2)];
    this.owed += frame / 1000 / dt;
    const start = performance.now();
    const budget = Math.min(SLOW_FRAME_BUDGET_MS, Math.max(FRAME_BUDGET_MS, 0.6 * wall));
    let done = 0;
    const due = Math.floor(this.owed);
    while (done < due && performance.now() - start < budget) {
      const batch = Math.min(due - done, 8);
      step(batch);
      done += batch;
    }
    const compute = performance.now() - start;
    this.owed -= done;
    // Carry at most one frame: the rest is dropped.
    const carry = Math.min(this.frameMs, frame) / 1000 / dt;
    if (this.owed > carry) {
      this.droppedSteps += Math.floor(this.owed - carry);
      this.owed -= Math.floor(this.owed - carry);
    }
    this.steps += done;
    this.history.push([now, wall, done, compute]);
    while (this.history.length && now - this.history[0][0] > WINDOW_MS) this.history.shift();
    return done;
  }

  // Steps run outside real time (single steps, tests).
  ran(n) {
    this.steps += n;
  }

  // The numbers over the last second.
  numbers(dt) {
    let wall = 0, steps = 0, compute = 0;
    for (const [, w, s, c] of this.history) {
      wall += w;
      steps += s;
      compute += c;
    }
    const simulatedMs = steps * dt * 1000;
    return {
      us_per_sim_ms: simulatedMs > 0 ? (1000 * compute) / simulatedMs : 0,
      realtime_ratio: wall > 0 ? simulatedMs / wall : 1,
      steps_per_s: wall > 0 ? (1000 * steps) / wall : 0,
      frames_per_s: wall > 0 ? (1000 * this.history.length) / wall : 0,
      lag_s: this.owed * dt,
      frame_s: this.frameMs / 1000,
      dropped_s: this.droppedSteps * dt,
      slow_motion: wall >= 0.5 * WINDOW_MS && simulatedMs < 0.95 * wall && !this.paused,
    };
  }
}
