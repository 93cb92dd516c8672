// The client's bootstrap and frame loop: fetch /api/scene.json and the room's glb, make the
// virtual texture, then draw every frame through one path (desktop, side-by-side stereo and
// each XR eye alike): VT beginFrame -> feedback pass per view (and the magnifier's) -> display
// pass per view -> the magnifier's inset -> stats.
//
// URL parameters: camera=x,y,z,tx,ty,tz[,fov] fixes the view (`gigascroll render --camera`'s
// convention); stereo=1 side-by-side; magnifier=1; stats=1; ipd=metres; size=WxH a fixed
// canvas size in pixels (tests); multiview=0 draws a pass per eye even where OVR_multiview2
// exists (multiview.js). Keys: WASD/QE walk, drag to look, M magnifier, V stereo,
// I stats panel. window.gigascroll is the test hook (see expose()).

import { DEFAULT_FOV, lookAt, anglesOf, parseCameraParam, vec3 } from './camera.js';
import { parseRoom } from './glb.js';
import { RoomRenderer } from './room_draw.js';
import { Magnifier, MAGNIFIER_VIEW } from './magnifier.js';
import { Stats } from './stats.js';
import { Controls } from './controls.js';
import { XrPresenter, xrAvailable } from './xr.js';
import { DEFAULT_IPD, desktopViews } from './desktop_views.js';
import { VirtualTexture } from './vt/virtual_texture.js';
import { MultiviewTarget, multiviewViews } from './multiview.js';
import { GpuTimer } from './gpu_timer.js';

const FEEDBACK_REDUCTION = 8;   // eyes' feedback at 1/8 resolution, the magnifier's at full
const MAX_SIZE = 8192;          // ?size's bound per side: a canvas WebGL2 can draw (and a tab can hold)
const { dot, sub } = vec3;

async function fetchOk(url, kind) {
  const r = await fetch(url);
  if (!r.ok) throw new Error(`${url}: HTTP ${r.status} ${(await r.text()).slice(0, 200)}`);
  return kind === 'json' ? r.json() : r.arrayBuffer();
}

function options(search) {
  const q = new URLSearchParams(search);
  const size = q.get('size') && /^(\d+)x(\d+)$/.exec(q.get('size'));
  if (q.get('size') && !(size && [size[1], size[2]].every((n) => Number(n) >= 1 && Number(n) <= MAX_SIZE)))
    throw new Error(`?size wants WxH, each in [1, ${MAX_SIZE}] pixels, got "${q.get('size')}"`);
  const ipd = q.get('ipd') === null ? DEFAULT_IPD : Number(q.get('ipd'));
  if (!(ipd >= 0 && ipd < 1)) throw new Error(`?ipd wants metres in [0, 1), got "${q.get('ipd')}"`);
  if (![null, '0', '1'].includes(q.get('multiview'))) throw new Error(`?multiview wants 0 or 1, got "${q.get('multiview')}"`);
  return { camera: parseCameraParam(search), stereo: q.get('stereo') === '1', magnifier: q.get('magnifier') === '1',
           stats: q.get('stats') === '1', ipd, multiview: q.get('multiview') !== '0', size: size ? [Number(size[1]), Number(size[2])] : null };
}

class App {
  constructor(canvas, gl, scene, meshes, vt, opts) {
    Object.assign(this, { canvas, gl, scene, vt, opts });
    this.room = new RoomRenderer(gl, meshes, vt, scene.display);
    this.magnifier = new Magnifier(gl);
    this.magnifier.toggle(opts.magnifier);
    this.stats = new Stats(document.getElementById('stats'));
    if (opts.stats) this.stats.toggle();
    this.stats.track(vt);
    this.stereo = opts.stereo;
    this.multiview = opts.multiview ? makeMultiview(gl, this.room) : null;
    this.timer = new GpuTimer(gl);
    this.frame = 0;
    this.afterFrame = null;   // test hook: fn({frame, gl, canvas, views}) after each frame
    this.captures = [];       // capture()'s waiting promises
    const c = opts.camera ?? scene.room.camera;
    this.fov = c.fov ?? DEFAULT_FOV;
    const start = lookAt(c.eye, c.target);
    this.controls = new Controls(canvas, start, scene.room.bounds, {
      fixed: Boolean(opts.camera),
      keys: { KeyM: () => this.magnifier.toggle(), KeyV: () => { this.stereo = !this.stereo; }, KeyI: () => this.stats.toggle() },
    });
    this.xr = new XrPresenter(gl, { eye: start.position, yaw: anglesOf(start).yaw },
                              (views, fb, t) => this.drawFrame(views, fb, t), () => this.magnifier.toggle());
  }

  // One frame of any mode: views (camera.js view records) into framebuffer (null: canvas).
  drawFrame(views, framebuffer, now) {
    const { gl, vt, room, magnifier } = this;
    const both = this.multiview !== null && multiviewViews(views);
    this.timer.poll();
    this.timer.begin(!both);   // a multiview pass cannot be timed (gpu_timer.js)
    vt.beginFrame(this.frame);
    views.forEach((v, i) => this.#feedback(i, v, FEEDBACK_REDUCTION));
    const centre = centreFrame(views);
    const lens = magnifier.on ? magnifier.view(centre, views[0].tanHalfY) : null;
    if (lens) {
      this.#feedback(MAGNIFIER_VIEW, lens, 1);
      magnifier.render(room, lens);
    }
    if (both) {
      this.multiview.bind(views[0].viewport[2], views[0].viewport[3]);
      room.drawViews(views);
      this.multiview.blit(views, framebuffer);
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, framebuffer);
    for (const v of views) {
      if (!both) room.drawView(v);
      if (lens) magnifier.composite(v, dot(sub(v.position, centre.position), centre.right));
    }
    this.timer.end();
    this.stats.gpu = { multiview: both, gpuMs: this.timer.ms };
    const feedbackViews = [...views.keys(), ...(lens ? [MAGNIFIER_VIEW] : [])];
    this.stats.update(this.frame, now, lens ? [...views, lens] : views, feedbackViews, vt.stats());
    this.afterFrame?.({ frame: this.frame, gl, canvas: this.canvas, views });
    if (this.captures.length && framebuffer === null) this.#capture();
    // The frame's commands (and the feedback readbacks' fences) go to the GPU now: a loop not
    // paced by the page's compositor (a fake XR device's timer) would otherwise leave the
    // fences unsignalled and the readbacks waiting.
    gl.flush();
    this.frame++;
  }

  // Replaces the fixed or starting view (camera.js frame of eye, target; fov degrees).
  setCamera(eye, target, fov = this.fov) {
    this.fov = fov;
    this.controls.start = lookAt(eye, target);
    Object.assign(this.controls, anglesOf(this.controls.start), { position: [...eye] });
  }

  // Resolves the waiting capture() promises with this frame's canvas pixels.
  #capture() {
    const { gl, canvas } = this, w = canvas.width, h = canvas.height;
    const pixels = new Uint8Array(w * h * 4);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, pixels);
    const result = { frame: this.frame, width: w, height: h, pixels };
    for (const resolve of this.captures.splice(0)) resolve(result);
  }

  #feedback(index, view, reduction) {
    this.vt.feedback.begin(index, view.viewport[2], view.viewport[3], reduction);
    this.room.drawFeedbackView(view);
    this.vt.feedback.end(index);
  }

  // The desktop loop (stopped while an XR session draws).
  run() {
    const tick = (now) => {
      requestAnimationFrame(tick);
      if (this.xr.session) return;
      this.#fitCanvas();
      const frame = this.controls.update();
      this.drawFrame(desktopViews(frame, this.fov, this.canvas.width, this.canvas.height, this.stereo, this.opts.ipd), null, now);
    };
    requestAnimationFrame(tick);
  }

  #fitCanvas() {
    const c = this.canvas, size = this.opts.size;
    const w = size ? size[0] : Math.max(1, Math.round(c.clientWidth * devicePixelRatio));
    const h = size ? size[1] : Math.max(1, Math.round(c.clientHeight * devicePixelRatio));
    if (c.width !== w || c.height !== h) Object.assign(c, { width: w, height: h });
  }
}

// The two-view target where the browser has OVR_multiview2 and the room's two-view programs
// compile, else null (the pass per eye).
function makeMultiview(gl, room) {
  const ext = gl.getExtension('OVR_multiview2');
  if (!ext) return null;
  try {
    room.enableMultiview();
    return new MultiviewTarget(gl, ext);
  } catch (e) {
    console.warn(`OVR_multiview2: ${e.message}; drawing a pass per eye`);
    return null;
  }
}

// The frame between the views' eyes (the magnifier looks from there along the first eye's gaze).
function centreFrame(views) {
  const f = views[0].frame, n = views.length;
  const position = [0, 1, 2].map((k) => views.reduce((s, v) => s + v.position[k], 0) / n);
  return { ...f, position };
}

function base64(bytes) {
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(s);
}

function showError(e) {
  const el = document.getElementById('error');
  if (el) { el.hidden = false; el.textContent = String(e?.message ?? e); }
  console.error(e);
}

// window.gigascroll: ready() (resolves once the room is drawn with the coarse tail resident),
// stats(), frame(), capture() (the next desktop frame's canvas as {frame, width, height,
// pixels: RGBA rows from the bottom, base64}), app (for tests), error.
function expose(readyPromise, getApp) {
  window.gigascroll = {
    ready: () => readyPromise,
    stats: () => ({ ...getApp()?.stats.numbers, vt: getApp()?.vt.stats() }),
    frame: () => getApp()?.frame ?? 0,
    capture: () => new Promise((resolve) => getApp().captures.push(resolve)).then((c) => ({ ...c, pixels: base64(c.pixels) })),
    get app() { return getApp(); },
    error: null,
  };
}

async function start() {
  let app = null, resolve, reject;
  const ready = new Promise((a, b) => { resolve = a; reject = b; });
  expose(ready, () => app);
  try {
    const opts = options(location.search);
    const canvas = document.getElementById('view');
    if (opts.size) Object.assign(canvas.style, { width: `${opts.size[0]}px`, height: `${opts.size[1]}px` });
    const gl = canvas.getContext('webgl2', { antialias: false, xrCompatible: true });
    if (!gl) throw new Error('this browser has no WebGL2');
    const scene = await fetchOk('/api/scene.json', 'json');
    const meshes = parseRoom(await fetchOk(scene.room.glb, 'buffer'));
    const vt = new VirtualTexture(gl, scene.pack, { tiles: scene.tiles });
    await vt.ready;
    app = new App(canvas, gl, scene, meshes, vt, opts);
    app.run();
    await new Promise((r) => { app.afterFrame = () => { app.afterFrame = null; r(); }; });
    setupVrButton(app);
    resolve(app.stats.numbers);
  } catch (e) {
    window.gigascroll.error = String(e?.message ?? e);
    showError(e);
    reject(e);
  }
}

async function setupVrButton(app) {
  const button = document.getElementById('enter-vr');
  if (!button || !(await xrAvailable())) return;
  button.hidden = false;
  app.xr.onEnd = () => { button.textContent = 'Enter VR'; };
  button.addEventListener('click', async () => {
    try {
      if (app.xr.session) await app.xr.exit();
      else await app.xr.enter();
      button.textContent = app.xr.session ? 'Exit VR' : 'Enter VR';
    } catch (e) {
      showError(e);
    }
  });
}

start();
