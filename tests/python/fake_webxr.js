// A small fake WebXR device for the client's tests, injected before the page's scripts
// (headless Chromium has no XR device and no navigator.xr.test). It offers an 'immersive-vr'
// session whose requestAnimationFrame hands out a frame with a viewer pose: a head standing
// still 1.5 m above the reference space's origin, looking along -z, and two eyes IPD apart
// along x, each with a symmetric projection (60 degrees vertical) and one half of a base
// layer whose framebuffer is the canvas's own (null), so a test reads both eyes back from the
// canvas. window.fakeXr.select() fires a controller's 'select'.
(() => {
  const W = 320, H = 240, IPD = 0.064, HEAD_Y = 1.5, FOV_Y = 60, NEAR = 0.05, FAR = 200;

  function projection() {
    const ty = Math.tan((FOV_Y * Math.PI) / 360), tx = (ty * W) / H;
    const a = (FAR + NEAR) / (NEAR - FAR), b = (2 * FAR * NEAR) / (NEAR - FAR);
    return new Float32Array([1 / tx, 0, 0, 0, 0, 1 / ty, 0, 0, 0, 0, a, -1, 0, 0, b, 0]);
  }

  function rigid(x, y, z) {
    const m = (sx, sy, sz) => new Float32Array([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, sx, sy, sz, 1]);
    return { position: { x, y, z, w: 1 }, orientation: { x: 0, y: 0, z: 0, w: 1 }, matrix: m(x, y, z),
             inverse: { matrix: m(-x, -y, -z) } };
  }

  const views = ['left', 'right'].map((eye, k) => ({
    eye, projectionMatrix: projection(), transform: rigid((k - 0.5) * IPD, HEAD_Y, 0),
  }));
  const pose = { transform: rigid(0, HEAD_Y, 0), views };
  const frame = { getViewerPose: () => pose };

  class XRWebGLLayer {
    constructor(session, gl) {
      Object.assign(this, { framebuffer: null, framebufferWidth: 2 * W, framebufferHeight: H });
    }
    getViewport(view) {
      return { x: view.eye === 'left' ? 0 : W, y: 0, width: W, height: H };
    }
  }

  const listeners = {};
  const state = { framesServed: 0, ended: false };
  const session = {
    renderState: { baseLayer: null },
    updateRenderState(s) { Object.assign(this.renderState, s); },
    async requestReferenceSpace(type) { return { type }; },
    // Paced by the page's own animation frames, as a headset's compositor paces a real
    // session (the page's loop skips its desktop frame while a session is on).
    requestAnimationFrame(cb) {
      return window.requestAnimationFrame((t) => {
        if (state.ended) return;
        state.framesServed++;
        cb(t, frame);
      });
    },
    addEventListener(type, fn) { (listeners[type] ||= []).push(fn); },
    async end() {
      state.ended = true;
      for (const fn of listeners.end ?? []) fn({ session });
    },
  };

  window.XRWebGLLayer = XRWebGLLayer;
  // Without an XR device the real makeXRCompatible never settles: the fake device's context
  // is compatible at once.
  WebGL2RenderingContext.prototype.makeXRCompatible = async function () {};
  Object.defineProperty(navigator, 'xr', {
    configurable: true,
    value: {
      async isSessionSupported(mode) { return mode === 'immersive-vr'; },
      async requestSession(mode) {
        if (mode !== 'immersive-vr') throw new Error(`fake XR: no ${mode}`);
        return session;
      },
    },
  });
  window.fakeXr = {
    session, IPD, W, H,
    get framesServed() { return state.framesServed; },
    select() { for (const fn of listeners.select ?? []) fn({ session }); },
  };
})();
