// The stats panel (toggle with a key) and its numbers, which window.gigascroll.stats() returns:
// fps, feedback ms, requests, tiles in flight, uploads a frame, hit rate, and the frames from
// the last stop of the camera until the view is exact (the virtual texturing paper's display
// latency after stopping, VT-mobile-VR Table 2: 4-5 frames there).
//
// A stop is the first frame of a run of frames drawn with the same views. The view is confirmed
// exact once every drawn view's feedback from a frame at or after the stop has been processed,
// asked for no tile that is not resident, and nothing is pending, in flight or waiting for
// upload. What is on screen was then final since the frame of the last upload (uploads land
// before that frame's draw), so the display latency is max(stop, last upload) - stop frames;
// the confirmation comes a readback later (framesStopToConfirmed).

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
    this.lastStopToExact = null;  // frames from the last stop to its exact view
    this.confirmedFrame = null;   // frame at which the exact view was confirmed
    this.lastUploadFrame = -1;
    this.uploadsTotal = 0;
    this.readbackFrames = new Map();  // feedback view -> frame of its newest processed readback
    this.numbers = {};
    // Set by the app before update(): whether the frame went through one multiview pass and
    // the GPU's median frame time in ms (gpu_timer.js; null without a timer query).
    this.gpu = { multiview: false, gpuMs: null };
  }

  // Wraps vt.feedback.poll to learn which frame each processed readback was drawn in.
  track(vt) {
    const poll = vt.feedback.poll.bind(vt.feedback);
    vt.feedback.poll = () => {
      const readbacks = poll();
      for (const r of readbacks) this.readbackFrames.set(r.view, Math.max(r.frame, this.readbackFrames.get(r.view) ?? -1));
      return readbacks;
    };
  }

  toggle() {
    if (this.panel) this.panel.hidden = !this.panel.hidden;
  }

  // Once a frame after drawing: frame number, time (ms), the frame's views, their feedback
  // view indices, vt.stats().
  update(frame, now, views, feedbackViews, vt) {
    this.times.push(now);
    if (this.times.length > FPS_WINDOW + 1) this.times.shift();
    if (sameViews(views, this.lastViews)) {
      if (this.stopFrame === null) this.stopFrame = frame - 1;   // the first frame at this pose
    } else {
      this.stopFrame = null;
      this.confirmedFrame = null;
    }
    this.lastViews = views.map((v) => ({ view: Float32Array.from(v.view), proj: Float32Array.from(v.proj) }));
    if (vt.uploads > 0) this.lastUploadFrame = frame;
    this.uploadsTotal += vt.uploads ?? 0;
    const readback = Math.min(...feedbackViews.map((i) => this.readbackFrames.get(i) ?? -1));
    if (this.confirmedFrame === null && isExact(vt, this.stopFrame, readback)) {
      this.confirmedFrame = frame;
      this.lastStopToExact = Math.max(this.stopFrame, this.lastUploadFrame) - this.stopFrame;
      this.lastStopToConfirmed = frame - this.stopFrame;
    }
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
      bytesReceived: vt.bytesReceived ?? 0,
      exact: this.confirmedFrame !== null,
      stopFrame: this.stopFrame,
      lastUploadFrame: this.lastUploadFrame,
      framesStopToExact: this.lastStopToExact,
      framesStopToConfirmed: this.lastStopToConfirmed ?? null,
      multiview: this.gpu.multiview,
      gpuMs: this.gpu.gpuMs,
    };
    if (this.panel && !this.panel.hidden) this.panel.textContent = this.text();
  }

  text() {
    const n = this.numbers, f = (x, d = 1) => (Number.isFinite(x) ? x.toFixed(d) : '-');
    return [
      `fps            ${f(n.fps)}`,
      `feedback ms    ${f(n.feedbackMs, 2)}`,
      `gpu ms         ${f(n.gpuMs, 2)}${n.multiview ? ' (multiview)' : ''}`,
      `requests       ${n.requests}`,
      `in flight      ${n.inFlight}`,
      `uploads/frame  ${n.uploads}`,
      `hit rate       ${f(100 * n.hitRate)} %`,
      `stop -> exact  ${n.framesStopToExact ?? '-'} frames${n.exact ? '' : ' (not yet)'}`,
    ].join('\n');
  }
}

// Whether the VT's state confirms the view exact (see the header): readbackFrame is the
// oldest of the drawn views' newest processed readbacks.
export function isExact(vt, stopFrame, readbackFrame) {
  if (stopFrame === null || stopFrame === undefined || readbackFrame < stopFrame) return false;
  return vt.commands === 0 && vt.pending === 0 && vt.inFlight === 0 && vt.uploads === 0;
}
