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
    this.held = new Map();     // key -> time (ms) from which its hold is not yet walked
    this.walked = new Map();   // key -> seconds held and released since the last update
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
      if (!this.held.has(e.code)) this.held.set(e.code, performance.now());
    });
    window.addEventListener('keyup', (e) => this.#release(e.code, performance.now()));
    window.addEventListener('blur', () => { for (const code of [...this.held.keys()]) this.#release(code, performance.now()); });
  }

  #release(code, now) {
    if (!this.held.has(code)) return;
    this.walked.set(code, (this.walked.get(code) ?? 0) + (now - this.held.get(code)) / 1000);
    this.held.delete(code);
  }

  // Seconds each key was down since the last update (a tap between two slow frames counts).
  #seconds(now) {
    const s = new Map(this.walked);
    for (const [code, since] of this.held) {
      s.set(code, (s.get(code) ?? 0) + (now - since) / 1000);
      this.held.set(code, now);
    }
    this.walked.clear();
    return s;
  }

  // Advances the pose by the time the walking keys were down since the last update; returns
  // the camera frame to draw.
  update(now = performance.now()) {
    const held = this.#seconds(now), t = (code) => held.get(code) ?? 0;
    if (this.fixed) return this.start;
    const step = SPEED * (this.held.has('ShiftLeft') || this.held.has('ShiftRight') ? 3 : 1);
    const forward = t('KeyW') - t('KeyS'), strafe = t('KeyD') - t('KeyA'), rise = t('KeyE') - t('KeyQ');
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
