// The feedback pass's targets and their asynchronous readback (tile determination, the
// virtual texturing paper §4.2.1; Mayer's thesis §3.4). Each view (0, 1: the eyes, 2: the
// magnifier) renders at reduced resolution into its own RGBA8 target, each pixel the 32-bit
// flat index of the tile it needs (sampler.glsl.js, vtFeedbackOut) or 0xFFFFFFFF for none.
// end() copies the target into a pixel-pack buffer and sets a fence; poll() hands back, per
// view, the newest readback whose fence has signalled (clientWaitSync with timeout 0: no
// stall), read with getBufferSubData. No synchronous readPixels into client memory ever happens on the
// frame path. A view whose buffers are all waiting skips its readback that frame; one whose
// fence has not signalled LATE_FRAMES frames later is read all the same (see there).

export const RING = 3;  // readbacks in flight per view
// A readback whose fence has not signalled this many frames after it was drawn is read all
// the same: its commands finished frames ago on any GPU (browsers keep two or three frames in
// flight), so getBufferSubData costs a round trip, not a wait for the GPU. On a headset fences
// signal within a few frames; headless chromium was seen to leave some unsignalled for good
// when frames come from setTimeout (a WebXR session's frames may), and tile determination
// must not stop there.
export const LATE_FRAMES = 12;

class ViewTarget {
  constructor(gl, width, height) {
    this.width = width;
    this.height = height;
    this.color = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, this.color);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGBA8, width, height);
    gl.bindTexture(gl.TEXTURE_2D, null);
    this.depth = gl.createRenderbuffer();
    gl.bindRenderbuffer(gl.RENDERBUFFER, this.depth);
    gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT24, width, height);
    gl.bindRenderbuffer(gl.RENDERBUFFER, null);
    this.framebuffer = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.framebuffer);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, this.color, 0);
    gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, this.depth);
    this.ring = [];
    for (let k = 0; k < RING; ++k) {
      const buffer = gl.createBuffer();
      gl.bindBuffer(gl.PIXEL_PACK_BUFFER, buffer);
      gl.bufferData(gl.PIXEL_PACK_BUFFER, width * height * 4, gl.STREAM_READ);
      this.ring.push({ buffer, sync: null, frame: -1, bytes: new Uint8Array(width * height * 4) });
    }
    gl.bindBuffer(gl.PIXEL_PACK_BUFFER, null);
  }
  dispose(gl) {
    gl.deleteFramebuffer(this.framebuffer);
    gl.deleteTexture(this.color);
    gl.deleteRenderbuffer(this.depth);
    for (const r of this.ring) {
      if (r.sync) gl.deleteSync(r.sync);
      gl.deleteBuffer(r.buffer);
    }
  }
}

// Whether a fence has signalled, without waiting: clientWaitSync with timeout 0 (never a
// stall) and the flush bit, which also pushes the fence to the GPU (chromium was seen never to
// signal a fence whose commands sat in its command buffer between setTimeout-driven frames,
// as a WebXR session's frames or a test's ticks may be).
function signalled(gl, sync) {
  const r = gl.clientWaitSync(sync, gl.SYNC_FLUSH_COMMANDS_BIT, 0);
  return r === gl.ALREADY_SIGNALED || r === gl.CONDITION_SATISFIED;
}

export class FeedbackPass {
  constructor(gl) {
    this.gl = gl;
    this.views = [];
    this.active = -1;
    this.frame = 0;
    this.pixelScale = [1, 1];
    this.skipped = 0;
    this.late = 0;
  }

  // Binds view's target at max(1, floor(display / reduction)) per axis (the core's 1/8
  // default for the eyes, 1 for the magnifier), clears it to "no request" and sets the
  // viewport; the caller then draws with vtFeedbackOut and calls vt.bind(program).
  begin(view, displayWidth, displayHeight, reduction = 8) {
    const gl = this.gl;
    const w = Math.max(1, Math.floor(displayWidth / reduction));
    const h = Math.max(1, Math.floor(displayHeight / reduction));
    let t = this.views[view];
    if (!t || t.width !== w || t.height !== h) {
      if (t) t.dispose(gl);
      t = this.views[view] = new ViewTarget(gl, w, h);
    }
    this.active = view;
    this.pixelScale = [w / displayWidth, h / displayHeight];
    gl.bindFramebuffer(gl.FRAMEBUFFER, t.framebuffer);
    gl.viewport(0, 0, w, h);
    gl.clearColor(1, 1, 1, 1);
    gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
  }

  // Starts view's readback into a free pixel-pack buffer (none free: skipped this frame).
  end(view) {
    const gl = this.gl, t = this.views[view];
    this.active = -1;
    this.pixelScale = [1, 1];
    const r = t && t.ring.find((x) => x.sync === null);
    if (!r) {
      ++this.skipped;
    } else {
      gl.bindBuffer(gl.PIXEL_PACK_BUFFER, r.buffer);
      gl.readPixels(0, 0, t.width, t.height, gl.RGBA, gl.UNSIGNED_BYTE, 0);
      gl.bindBuffer(gl.PIXEL_PACK_BUFFER, null);
      r.sync = gl.fenceSync(gl.SYNC_GPU_COMMANDS_COMPLETE, 0);
      r.frame = this.frame;
      gl.flush();
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  }

  // Per view, the newest signalled (or late) readback as {view, frame, width, height, keys:
  // Uint32Array} (row 0 at the bottom, as GL reads); older ones are dropped.
  poll() {
    const gl = this.gl, out = [];
    this.views.forEach((t, view) => {
      if (!t) return;
      let best = null;
      for (const r of t.ring) {
        if (!r.sync) continue;
        if (!signalled(gl, r.sync)) {
          if (this.frame - r.frame < LATE_FRAMES) continue;
          ++this.late;
        }
        gl.deleteSync(r.sync);
        r.sync = null;
        if (!best || r.frame > best.frame) best = r;
      }
      if (!best) return;
      gl.bindBuffer(gl.PIXEL_PACK_BUFFER, best.buffer);
      gl.getBufferSubData(gl.PIXEL_PACK_BUFFER, 0, best.bytes);
      gl.bindBuffer(gl.PIXEL_PACK_BUFFER, null);
      out.push({ view, frame: best.frame, width: t.width, height: t.height,
                 keys: new Uint32Array(best.bytes.buffer) });
    });
    return out;
  }

  // Whether any readback is still waiting for its fence.
  get pending() {
    return this.views.some((t) => t && t.ring.some((r) => r.sync !== null));
  }

  dispose() {
    for (const t of this.views) if (t) t.dispose(this.gl);
    this.views = [];
  }
}
