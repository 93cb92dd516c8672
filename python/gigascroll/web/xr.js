// WebXR: an `immersive-vr` session behind the "Enter VR" button. Each XR frame's views (one
// per eye: its pose, projection matrix and viewport in the base layer's framebuffer) become
// the same view records the desktop draws (camera.js makeView's shape), drawn by the same
// per-view function: both eyes in one OVR_multiview2 pass where the browser has it
// (multiview.js), else one pass per eye.
//
// The room's coordinates are placed on the headset's: the reference space's origin (the
// floor under the visitor with 'local-floor', the head with 'local') is put at the room's
// suggested eye, turned to face its target. Only the API below is used, so a small fake
// navigator.xr (tests) drives the whole path.

import { multiply } from './camera.js';

// The room-from-XR transform (column-major): a turn about y by yaw, then a translation.
function placement(origin, yaw) {
  const c = Math.cos(yaw), s = Math.sin(yaw);
  return new Float32Array([c, 0, -s, 0, 0, 1, 0, 0, s, 0, c, 0, origin[0], origin[1], origin[2], 1]);
}

function invertRigid(m) {
  // transpose of the rotation, -R^T t
  const r = [m[0], m[4], m[8], 0, m[1], m[5], m[9], 0, m[2], m[6], m[10], 0];
  const t = [m[12], m[13], m[14]];
  return new Float32Array([...r,
    -(r[0] * t[0] + r[4] * t[1] + r[8] * t[2]), -(r[1] * t[0] + r[5] * t[1] + r[9] * t[2]),
    -(r[2] * t[0] + r[6] * t[1] + r[10] * t[2]), 1]);
}

export async function xrAvailable() {
  try {
    return Boolean(navigator.xr && (await navigator.xr.isSessionSupported('immersive-vr')));
  } catch {
    return false;
  }
}

export class XrPresenter {
  // gl: the page's context; start: {eye, yaw} of the room's suggested view; drawFrame(views,
  // framebuffer, time): the app's frame; onSelect: a controller's select (the magnifier).
  constructor(gl, start, drawFrame, onSelect) {
    Object.assign(this, { gl, start, drawFrame, onSelect });
    this.session = null;
    this.frames = 0;
    this.onEnd = null;   // called when a session ends (the headset's button or exit())
  }

  async enter() {
    const xr = navigator.xr;
    const session = await xr.requestSession('immersive-vr', { optionalFeatures: ['local-floor'] });
    if (!this.gl.getContextAttributes().xrCompatible) await this.gl.makeXRCompatible();
    const layer = new XRWebGLLayer(session, this.gl);
    session.updateRenderState({ baseLayer: layer });
    let floor = true, space;
    try {
      space = await session.requestReferenceSpace('local-floor');
    } catch {
      floor = false;
      space = await session.requestReferenceSpace('local');
    }
    const e = this.start.eye;
    this.roomFromXr = placement([e[0], floor ? 0 : e[1], e[2]], this.start.yaw);
    this.xrFromRoom = invertRigid(this.roomFromXr);
    this.session = session;
    this.space = space;
    session.addEventListener('select', () => this.onSelect?.());
    session.addEventListener('end', () => { this.session = null; this.onEnd?.(); });
    session.requestAnimationFrame((t, f) => this.#frame(t, f));
  }

  async exit() {
    await this.session?.end();
  }

  // The XR frame's views in room coordinates, in the shape of camera.js makeView.
  views(frame) {
    const pose = frame.getViewerPose(this.space);
    if (!pose) return null;
    const layer = this.session.renderState.baseLayer;
    return pose.views.map((v) => {
      const vp = layer.getViewport(v);
      const room = multiply(this.roomFromXr, v.transform.matrix);
      return {
        view: multiply(v.transform.inverse.matrix, this.xrFromRoom),
        proj: Float32Array.from(v.projectionMatrix),
        position: [room[12], room[13], room[14]],
        frame: { position: [room[12], room[13], room[14]], right: [room[0], room[1], room[2]],
                 up: [room[4], room[5], room[6]], forward: [-room[8], -room[9], -room[10]] },
        tanHalfY: 1 / v.projectionMatrix[5],
        viewport: [vp.x, vp.y, vp.width, vp.height],
        eye: v.eye,
      };
    });
  }

  #frame(time, frame) {
    const session = this.session;
    if (!session) return;
    session.requestAnimationFrame((t, f) => this.#frame(t, f));
    const views = this.views(frame);
    if (!views) return;
    this.frames++;
    this.drawFrame(views, session.renderState.baseLayer.framebuffer, time);
  }
}
