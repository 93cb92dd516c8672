// The GPU time of each frame's draws from EXT_disjoint_timer_query_webgl2, where the browser
// offers it: a TIME_ELAPSED_EXT query around the frame, polled in later frames (a result is
// read only once QUERY_RESULT_AVAILABLE says so: never waited on), dropped when the GPU
// reports a disjoint (GPU_DISJOINT_EXT: a clock change or a context switch spoilt it). ms is
// the median of the last `window` results, or null without the extension or any result.
// On SwiftShader the "GPU" is CPU emulation: its figures are only relative.
//
// OVR_multiview2 forbids a draw into a multiview framebuffer while a TIME_ELAPSED_EXT query is
// active (INVALID_OPERATION), and WebGL browsers give TIMESTAMP_EXT no counter bits, so a frame
// drawn in one multiview pass is not timed: begin(false) skips it and forgets the earlier
// results, and ms stays null while the multiview path draws (?multiview=0 measures the pass
// per eye).

const MAX_PENDING = 8;   // queries in flight at most (a driver that never answers stops new ones)

export class GpuTimer {
  constructor(gl, window = 30) {
    Object.assign(this, { gl, window });
    this.ext = gl.getExtension('EXT_disjoint_timer_query_webgl2');
    this.pending = [];
    this.samples = [];
    this.active = null;
    this.disjoints = 0;
    this.generation = 0;
  }

  // Starts the frame's query; timed false: the frame cannot be timed (see the header).
  begin(timed = true) {
    const gl = this.gl;
    if (!timed) {
      this.generation = this.generation + 1;
      this.samples.length = 0;
    }
    if (!this.ext || !timed || this.active || this.pending.length >= MAX_PENDING) return;
    this.active = gl.createQuery();
    this.active.generation = this.generation;   // results of older generations are dropped
    gl.beginQuery(this.ext.TIME_ELAPSED_EXT, this.active);
  }

  end() {
    if (!this.active) return;
    this.gl.endQuery(this.ext.TIME_ELAPSED_EXT);
    this.pending.push(this.active);
    this.active = null;
  }

  // Collects the results that are available, oldest first; none is waited for.
  poll() {
    const gl = this.gl;
    if (!this.ext) return;
    const disjoint = gl.getParameter(this.ext.GPU_DISJOINT_EXT);
    while (this.pending.length && gl.getQueryParameter(this.pending[0], gl.QUERY_RESULT_AVAILABLE)) {
      const q = this.pending.shift();
      const ns = gl.getQueryParameter(q, gl.QUERY_RESULT);
      gl.deleteQuery(q);
      if (!disjoint && ns > 0 && q.generation === this.generation) this.samples.push(ns / 1e6);
    }
    if (disjoint) {
      this.disjoints++;
      this.samples.length = 0;
    }
    if (this.samples.length > this.window) this.samples.splice(0, this.samples.length - this.window);
  }

  get ms() {
    if (!this.ext || !this.samples.length) return null;
    const s = [...this.samples].sort((a, b) => a - b), n = s.length;
    return n % 2 ? s[n >> 1] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
  }
}
