// The stats panel (toggle with a key) and its numbers, which window.gigascroll.stats() returns:
// fps, feedback ms, requests, tiles in flight, uploads a frame, hit rate, and the frames from
// the last stop of the camera until the view is exact (the virtual texturing paper's display
// latency after stopping, seed 000 Table 2: 4-5 frames there).
//
// "Exact": the virtual texture has processed a feedback readback of a frame drawn at or after
// the stop, that readback asked for no tile that is not resident, and nothing is pending, in
// flight or waiting for upload: what is on screen is then what the full resident set would
// draw. A stop is the first frame whose views equal the previous frame's.

const FPS_WINDOW = 30;   // frames averaged for the fps figure

function sameViews(a, b) {
  if (!a || !b || a.length !== b.length) return false;
  return a.every((v, i) => v.view.every((x, k) => x === b[i].view[k]) && v.proj.every((x, k) => x === b[i].proj[k]));
}

export class Stats {
  constructor(panel) {
    this.panel = panel;
    this.times = [];
    this.lastViews = null;
    this.stopFrame = null;        // first frame of the current stop, null while moving
    this.exactFrame = null;       // first exact frame since stopFrame
    this.lastStopToExact = null;  // frames from the last stop to its exact view
    this.uploadsTotal = 0;
    this.bytesTotal = 0;
    this.numbers = {};
  }

  toggle() {
    if (this.panel) this.panel.hidden = !this.panel.hidden;
  }

  // Once a frame after drawing: frame number, time (ms), the frame's views, vt.stats().
  update(frame, now, views, vt) {
    this.times.push(now);
    if (this.times.length > FPS_WINDOW + 1) this.times.shift();
    if (sameViews(views, this.lastViews)) {
      if (this.stopFrame === null) this.stopFrame = frame;
    } else {
      this.stopFrame = null;
      this.exactFrame = null;
    }
    this.lastViews = views.map((v) => ({ view: Float32Array.from(v.view), proj: Float32Array.from(v.proj) }));
    const exact = isExact(vt, this.stopFrame);
    if (exact && this.exactFrame === null) {
      this.exactFrame = frame;
      this.lastStopToExact = frame - this.stopFrame;
    }
    this.uploadsTotal += vt.uploads ?? 0;
    const span = this.times.length > 1 ? this.times[this.times.length - 1] - this.times[0] : 0;
    this.numbers = {
      frame,
      fps: span > 0 ? (1000 * (this.times.length - 1)) / span : 0,
      feedbackMs: vt.feedbackMs ?? 0,
      requests: vt.requests ?? 0,
      inFlight: vt.inFlight ?? 0,
      uploads: vt.uploads ?? 0,
      hitRate: vt.hitRate ?? 0,
      resident: vt.resident ?? 0,
      uploadsTotal: this.uploadsTotal,
      exact: this.exactFrame !== null,
      stopFrame: this.stopFrame,
      framesStopToExact: this.lastStopToExact,
    };
    if (this.panel && !this.panel.hidden) this.panel.textContent = this.text();
  }

  text() {
    const n = this.numbers, f = (x, d = 1) => (Number.isFinite(x) ? x.toFixed(d) : '-');
    return [
      `fps            ${f(n.fps)}`,
      `feedback ms    ${f(n.feedbackMs, 2)}`,
      `requests       ${n.requests}`,
      `in flight      ${n.inFlight}`,
      `uploads/frame  ${n.uploads}`,
      `hit rate       ${f(100 * n.hitRate)} %`,
      `stop -> exact  ${n.framesStopToExact ?? '-'} frames${n.exact ? '' : ' (not yet)'}`,
    ].join('\n');
  }
}

// Whether the VT's state at this frame makes the view exact (see the header).
export function isExact(vt, stopFrame) {
  if (stopFrame === null || stopFrame === undefined) return false;
  return (vt.feedbackFrame ?? -1) >= stopFrame && (vt.missing ?? 1) === 0 && (vt.pending ?? 0) === 0
    && (vt.inFlight ?? 0) === 0 && (vt.uploads ?? 0) === 0;
}
