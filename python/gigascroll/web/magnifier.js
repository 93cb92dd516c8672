// The magnifier: the virtual texturing paper's second camera (VT-mobile-VR §4.1), a narrower field
// of view along the viewer's gaze, drawn offscreen and shown as an inset in every view. It has
// its own feedback pass at full resolution (view 2), so the tiles it needs (finer levels than
// the main view's) stream in as well.

import { makeView } from './camera.js';
import { BLIT_FS, BLIT_VS, HEADER } from './display.glsl.js';
import { makeProgram, makeTarget } from './gl_util.js';

export const MAGNIFIER_VIEW = 2;   // the feedback view index of the magnifier
// The inset is seen this far away in stereo: each eye's copy is shifted by the disparity of
// that distance, so it does not float at infinity in front of nearer walls.
export const INSET_DISTANCE = 0.5;

export class Magnifier {
  // size: the offscreen image's side in pixels (the paper's magnifier feedback is 512^2);
  // zoom: the magnification (tan of the half angle divided by it).
  constructor(gl, { size = 256, zoom = 4, inset = 0.4 } = {}) {
    this.gl = gl;
    this.size = size;
    this.zoom = zoom;
    this.inset = inset;   // the inset's side as a fraction of the view's height
    this.on = false;
    this.target = makeTarget(gl, size, size);
    this.blit = makeProgram(gl, HEADER + BLIT_VS, HEADER + BLIT_FS, 'magnifier blit');
    this.toggles = 0;
  }

  toggle(on = !this.on) {
    if (on !== this.on) this.toggles++;
    this.on = on;
  }

  // The magnifier's view: the centre eye's frame with the eye's vertical field of view
  // (given by the tangent of its half angle) narrowed zoom times.
  view(frame, tanHalfY) {
    const t = tanHalfY / this.zoom;
    return makeView(frame, (360 / Math.PI) * Math.atan(t), [0, 0, this.size, this.size]);
  }

  // Draws view (from view()) into the offscreen target with the room's per-view draw.
  render(room, view) {
    const gl = this.gl;
    gl.bindFramebuffer(gl.FRAMEBUFFER, this.target.framebuffer);
    room.drawView(view);
  }

  // The inset in the lower right of a view of the bound framebuffer, square in pixels;
  // eyeOffset: the eye's distance (m) along the head's right vector from the head's centre
  // (0 for one eye), which shifts the inset by the disparity of INSET_DISTANCE.
  composite(view, eyeOffset = 0) {
    const gl = this.gl, [x, y, w, h] = view.viewport;
    const side = Math.max(8, Math.round(this.inset * Math.min(w, h)));
    const margin = Math.round(0.04 * Math.min(w, h));
    gl.viewport(x, y, w, h);
    gl.disable(gl.DEPTH_TEST);
    gl.useProgram(this.blit.program);
    gl.activeTexture(gl.TEXTURE0);
    gl.bindTexture(gl.TEXTURE_2D, this.target.texture);
    gl.uniform1i(this.blit.uniforms.uImage, 0);
    gl.uniform1f(this.blit.uniforms.uRim, 1.5 / side);
    const shift = (-eyeOffset * view.proj[0]) / INSET_DISTANCE;   // NDC: x_eye / (z tan_half_x)
    // Both eyes' copies stay inside their views: the one shifted right touches the margin.
    const x1 = 1 - (2 * margin) / w - Math.abs(shift) + shift, y0 = -1 + (2 * margin) / h;
    gl.uniform4f(this.blit.uniforms.uRect, x1 - (2 * side) / w, y0, x1, y0 + (2 * side) / h);
    gl.drawArrays(gl.TRIANGLE_STRIP, 0, 4);
  }
}
