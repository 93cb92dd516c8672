// Desktop walking: drag with the mouse to look, WASD to walk (horizontally), Q / E down and
// up, Shift to hurry; the mode keys (magnifier, stereo, stats) go to callbacks. The pose stays
// inside the room's bounds (with a margin), so nobody walks through a wall.

import { anglesOf, frameFromAngles } from './camera.js';

const SPEED = 1.0;          // m/s, the paper's walking speed
const MARGIN = 0.15;        // m kept from the room's walls, floor and ceiling
const LOOK = 0.004;         // radians per dragged pixel

export class Controls {
  // start: camera.js frame; bounds [[x0,y0,z0],[x1,y1,z1]]; keys: {KeyM: fn, ...}.
  constructor(element, start, bounds, { keys = {}, fixed = false } = {}) {
    this.position = [...start.position];
    ({ yaw: this.yaw, pitch: this.pitch } = anglesOf(start));
    this.bounds = bounds;
    this.fixed = fixed;
    this.start = start;
    this.held = new Set();
    this.keys = keys;
    let drag = null;
    element.addEventListener('pointerdown', (e) => { drag = [e.clientX, e.clientY]; element.setPointerCapture?.(e.pointerId); });
    element.addEventListener('pointerup', () => { drag = null; });
    element.addEventListener('pointermove', (e) => {
      if (!drag || this.fixed) return;
      this.yaw -= (e.clientX - drag[0]) * LOOK;   // drag right: turn right
      this.pitch = Math.max(-1.5, Math.min(1.5, this.pitch - (e.clientY - drag[1]) * LOOK));
      drag = [e.clientX, e.clientY];
    });
    window.addEventListener('keydown', (e) => {
      if (this.keys[e.code] && !e.repeat) this.keys[e.code]();
      this.held.add(e.code);
    });
    window.addEventListener('keyup', (e) => this.held.delete(e.code));
    window.addEventListener('blur', () => this.held.clear());
  }

  // Advances the pose by dt seconds of held keys; returns the camera frame to draw.
  update(dt) {
    if (this.fixed) return this.start;
    const h = this.held, step = SPEED * (h.has('ShiftLeft') || h.has('ShiftRight') ? 3 : 1) * Math.min(dt, 0.1);
    const forward = (h.has('KeyW') ? 1 : 0) - (h.has('KeyS') ? 1 : 0);
    const strafe = (h.has('KeyD') ? 1 : 0) - (h.has('KeyA') ? 1 : 0);
    const rise = (h.has('KeyE') ? 1 : 0) - (h.has('KeyQ') ? 1 : 0);
    const s = Math.sin(this.yaw), c = Math.cos(this.yaw);
    const p = this.position;
    p[0] += step * (-s * forward + c * strafe);
    p[2] += step * (-c * forward - s * strafe);
    p[1] += step * rise;
    if (this.bounds)
      for (let i = 0; i < 3; i++)
        p[i] = Math.max(this.bounds[0][i] + MARGIN, Math.min(this.bounds[1][i] - MARGIN, p[i]));
    return frameFromAngles(p, this.yaw, this.pitch);
  }
}
