// The room on the GPU and the one per-view draw function every mode goes through (desktop,
// side-by-side stereo, each XR eye, the magnifier): a view is {view, proj, position, viewport}
// from camera.js, drawn into whatever framebuffer is bound.

import { multiply } from './camera.js';
import { ATTRIBUTES, HEADER, PAINTING_FS, ROOM_FS, ROOM_VS, displayMapping } from './display.glsl.js';
import { makeProgram } from './gl_util.js';
import { FEEDBACK_FS } from './feedback.glsl.js';
import { openEdges } from './crack_fill.js';
import { multiviewSource } from './multiview.js';

function upload(gl, mesh) {
  const vao = gl.createVertexArray();
  const lines = mesh.painting < 0 ? uploadLines(gl, openEdges(mesh)) : null;
  gl.bindVertexArray(vao);
  attribute(gl, ATTRIBUTES.position, mesh.positions, 3);
  attribute(gl, ATTRIBUTES.irradianceFront, mesh.irradianceFront, 3);
  attribute(gl, ATTRIBUTES.irradianceBack, mesh.irradianceBack, 3);
  if (mesh.texcoords) attribute(gl, ATTRIBUTES.texcoord, mesh.texcoords, 2);
  else gl.vertexAttrib2f(ATTRIBUTES.texcoord, 0, 0);
  gl.vertexAttrib3f(ATTRIBUTES.normal, 0, 0, 0);
  let indexType = null, count = mesh.vertexCount;
  if (mesh.indices) {
    const buffer = gl.createBuffer();
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, buffer);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, mesh.indices, gl.STATIC_DRAW);
    indexType = { 1: gl.UNSIGNED_BYTE, 2: gl.UNSIGNED_SHORT, 4: gl.UNSIGNED_INT }[mesh.indices.BYTES_PER_ELEMENT];
    count = mesh.indices.length;
  }
  gl.bindVertexArray(null);
  return { vao, indexType, count, albedo: mesh.albedo, emission: mesh.emission, painting: mesh.painting, lines,
           corners: boxCorners(mesh.positions) };
}

// The 8 corners of a position array's bounding box.
function boxCorners(p) {
  const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
  for (let i = 0; i < p.length; i += 3)
    for (let k = 0; k < 3; k++) {
      lo[k] = Math.min(lo[k], p[i + k]);
      hi[k] = Math.max(hi[k], p[i + k]);
    }
  return [0, 1, 2, 3, 4, 5, 6, 7].map((b) => [b & 1 ? hi[0] : lo[0], b & 2 ? hi[1] : lo[1], b & 4 ? hi[2] : lo[2]]);
}

// Whether a box lies wholly outside one plane of the view's frustum (clip space: outside
// x = +-w, y = +-w, z = +-w); conservative, so nothing visible is ever skipped.
export function outsideFrustum(viewProj, corners) {
  const m = viewProj, out = [0, 0, 0, 0, 0, 0];
  for (const [x, y, z] of corners) {
    const c = [0, 1, 2, 3].map((r) => m[r] * x + m[4 + r] * y + m[8 + r] * z + m[12 + r]);
    const w = c[3];
    out[0] += c[0] < -w; out[1] += c[0] > w; out[2] += c[1] < -w;
    out[3] += c[1] > w; out[4] += c[2] < -w; out[5] += c[2] > w;
  }
  return out.some((n) => n === corners.length);
}

function attribute(gl, location, data, size) {
  const buffer = gl.createBuffer();
  gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
  gl.bufferData(gl.ARRAY_BUFFER, data, gl.STATIC_DRAW);
  gl.enableVertexAttribArray(location);
  gl.vertexAttribPointer(location, size, gl.FLOAT, false, 0, 0);
}

// The crack-fill line list of a room surface (crack_fill.js), or null.
function uploadLines(gl, edges) {
  if (!edges) return null;
  const vao = gl.createVertexArray();
  gl.bindVertexArray(vao);
  attribute(gl, ATTRIBUTES.position, edges.positions, 3);
  attribute(gl, ATTRIBUTES.irradianceFront, edges.irradianceFront, 3);
  attribute(gl, ATTRIBUTES.irradianceBack, edges.irradianceBack, 3);
  attribute(gl, ATTRIBUTES.normal, edges.normals, 3);
  gl.vertexAttrib2f(ATTRIBUTES.texcoord, 0, 0);
  gl.bindVertexArray(null);
  return { vao, count: edges.vertexCount };
}

export class RoomRenderer {
  // meshes: glb.parseRoom's list; vt: the VirtualTexture facade; display: scene.json's display.
  constructor(gl, meshes, vt, display) {
    this.gl = gl;
    this.vt = vt;
    this.exposure = display.exposure;
    const map = displayMapping(display);
    const vs = HEADER + ROOM_VS;
    this.room = makeProgram(gl, vs, HEADER + map + ROOM_FS, 'room');
    this.painting = makeProgram(gl, vs, HEADER + vt.glsl + map + PAINTING_FS, 'painting');
    this.feedback = makeProgram(gl, vs, HEADER + vt.glsl + FEEDBACK_FS, 'feedback');
    // Room surfaces first: in the feedback pass they lay the depth that hides paintings.
    this.meshes = meshes.map((m) => upload(gl, m)).sort((a, b) => (a.painting >= 0) - (b.painting >= 0));
    this.triangles = this.meshes.reduce((n, m) => n + m.count / 3, 0);
    this.sources = { vs, room: HEADER + map + ROOM_FS, painting: HEADER + vt.glsl + map + PAINTING_FS };
    this.multiview = null;   // the two-view programs once enableMultiview() made them
  }

  // Builds the display programs for OVR_multiview2 (multiview.js); throws if the browser
  // cannot compile them (the caller then keeps the pass per eye).
  enableMultiview() {
    const { gl, sources: s } = this;
    const vs = multiviewSource(s.vs, HEADER, true), fs = (src) => multiviewSource(src, HEADER, false);
    this.multiview = { room: makeProgram(gl, vs, fs(s.room), 'multiview room'),
                       painting: makeProgram(gl, vs, fs(s.painting), 'multiview painting') };
  }

  // The display pass of one view into the bound framebuffer: clears its viewport, draws the
  // room surfaces and the paintings (their albedo through the virtual texture).
  drawView(view) {
    const gl = this.gl;
    this.#begin(view);
    const viewProj = multiply(view.proj, view.view);
    this.#drawMeshes(this, (u) => {
      gl.uniformMatrix4fv(u.uViewProj, false, viewProj);
      gl.uniform3fv(u.uEye, view.position);
    }, (m) => outsideFrustum(viewProj, m.corners));
  }

  // Both views (of one size) in one OVR_multiview2 pass into the bound two-layer target
  // (multiview.js, after enableMultiview()): gl_ViewID_OVR picks each view's matrices and eye;
  // a mesh is skipped only when it lies outside both views' frusta.
  drawViews(views) {
    const gl = this.gl, viewProjs = views.map((v) => multiply(v.proj, v.view));
    this.#begin({ viewport: [0, 0, views[0].viewport[2], views[0].viewport[3]] });
    const matrices = new Float32Array(32), eyes = new Float32Array(6);
    viewProjs.forEach((m, k) => matrices.set(m, 16 * k));
    views.forEach((v, k) => eyes.set(v.position, 3 * k));
    this.#drawMeshes(this.multiview, (u) => {
      gl.uniformMatrix4fv(u.uViewProjs, false, matrices);
      gl.uniform3fv(u.uEyes, eyes);
    }, (m) => viewProjs.every((vp) => outsideFrustum(vp, m.corners)));
  }

  // The room surfaces, the paintings and the crack-fill lines with programs {room, painting};
  // setView(uniforms) sets a program's view uniforms; hidden(mesh) culls.
  #drawMeshes(programs, setView, hidden) {
    const gl = this.gl;
    this.drawn = 0;
    for (const [prog, paintings] of [[programs.room, false], [programs.painting, true]]) {
      gl.useProgram(prog.program);
      if (paintings) this.vt.bind(prog.program);
      setView(prog.uniforms);
      gl.uniform1f(prog.uniforms.uExposure, this.exposure);
      for (const m of this.meshes) {
        if ((m.painting >= 0) !== paintings || hidden(m)) continue;
        ++this.drawn;
        if (paintings) gl.uniform1i(prog.uniforms.uPainting, m.painting);
        else gl.uniform3fv(prog.uniforms.uAlbedo, m.albedo);
        gl.uniform3fv(prog.uniforms.uEmission, m.emission);
        this.#draw(m);
      }
    }
    this.#fillCracks(programs.room, hidden);
    gl.bindVertexArray(null);
  }

  // The feedback pass of one view, between vt.feedback.begin(i) and end(i) (which bind the
  // reduced-resolution target): every surface writes depth so hidden paintings ask for
  // nothing; paintings write their tile requests.
  drawFeedbackView(view) {
    const gl = this.gl, prog = this.feedback;
    gl.enable(gl.DEPTH_TEST);
    gl.disable(gl.CULL_FACE);
    gl.useProgram(prog.program);
    this.vt.bind(prog.program);
    const viewProj = multiply(view.proj, view.view);
    gl.uniformMatrix4fv(prog.uniforms.uViewProj, false, viewProj);
    for (const m of this.meshes) {
      if (outsideFrustum(viewProj, m.corners)) continue;
      gl.colorMask(m.painting >= 0, m.painting >= 0, m.painting >= 0, m.painting >= 0);
      gl.uniform1i(prog.uniforms.uPainting, Math.max(0, m.painting));
      this.#draw(m);
    }
    gl.colorMask(true, true, true, true);
    gl.bindVertexArray(null);
  }

  // The room surfaces' open edges as lines, after every triangle: they land only where the
  // depth test finds nothing nearer, i.e. in the cracks (crack_fill.js).
  #fillCracks(prog, hidden) {
    const gl = this.gl;
    gl.useProgram(prog.program);
    gl.uniform1i(prog.uniforms.uLines, 1);
    for (const m of this.meshes) {
      if (!m.lines || hidden(m)) continue;
      gl.uniform3fv(prog.uniforms.uAlbedo, m.albedo);
      gl.uniform3fv(prog.uniforms.uEmission, m.emission);
      gl.bindVertexArray(m.lines.vao);
      gl.drawArrays(gl.LINES, 0, m.lines.count);
    }
    gl.uniform1i(prog.uniforms.uLines, 0);
  }

  #begin(view) {  // viewport, scissored clear, depth test
    const gl = this.gl, [x, y, w, h] = view.viewport;
    gl.viewport(x, y, w, h);
    gl.enable(gl.SCISSOR_TEST);
    gl.scissor(x, y, w, h);
    gl.clearColor(0, 0, 0, 1);
    gl.clearDepth(1);
    gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
    gl.disable(gl.SCISSOR_TEST);
    gl.enable(gl.DEPTH_TEST);
    gl.depthFunc(gl.LESS);
    gl.disable(gl.CULL_FACE);  // surfaces are lit on both sides (front and back irradiance)
    gl.disable(gl.BLEND);
  }

  #draw(m) {
    const gl = this.gl;
    gl.bindVertexArray(m.vao);
    if (m.indexType !== null) gl.drawElements(gl.TRIANGLES, m.count, m.indexType, 0);
    else gl.drawArrays(gl.TRIANGLES, 0, m.count);
  }
}

