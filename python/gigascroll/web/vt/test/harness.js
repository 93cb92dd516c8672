// The virtual texture's test page (harness.html): window.vtTest drives the GPU virtual texture
// without the app, for tests/python/test_web_vt.py and `gigascroll bench web`:
//   await vtTest.init({slots, scene})   the pack from scene (default /api/scene.json; the
//                                       server has none without a room), tails resident
//   await vtTest.insertTiles(keys)      fetch [p, l, x, y] tiles and make them resident
//   vtTest.sampleProbes(probes, hw)     [p, u, v, lod] x n -> vtSample's RGBA (float target;
//                                       hw: the hardware-bilinear variant)
//   vtTest.render(view, placements)     the display pass's vtSample at vtLod: RGBA8, base64
//   await vtTest.feedback(views, placements)
//                                       one feedback pass per view, read back asynchronously:
//                                       [{view, width, height, indices (uint32 little-endian,
//                                       base64), keys (index -> [p, l, x, y])}]
//   await vtTest.stream(views, placements, maxFrames)
//                                       the whole runtime from a cold cache until quiet
//   await vtTest.benchFeedback(views, placements, frames)
//                                       per frame: beginFrame's feedback time (poll +
//                                       processing) with the views' passes drawn every frame
// A view is {view, camera: [ex, ey, ez, tx, ty, tz, fov], display: [w, h], reduction}; the
// camera is `gigascroll render --camera`'s convention (vertical fov in degrees, y up). A
// placement is scene.json's slot: {painting, origin, u_axis, v_axis, width_m, height_m}.
import { makeTarget } from "../../gl_util.js";
import { VirtualTexture } from "../virtual_texture.js";

const canvas = document.getElementById("canvas");
const gl = canvas.getContext("webgl2", { antialias: false });
let scene = null, vt = null;

function compile(vsSource, fsSource) {
  const shader = (type, src) => {
    const s = gl.createShader(type);
    gl.shaderSource(s, src);
    gl.compileShader(s);
    if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(gl.getShaderInfoLog(s));
    return s;
  };
  const p = gl.createProgram();
  gl.attachShader(p, shader(gl.VERTEX_SHADER, vsSource));
  gl.attachShader(p, shader(gl.FRAGMENT_SHADER, fsSource));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(gl.getProgramInfoLog(p));
  return p;
}

const HEADER = "#version 300 es\nprecision highp float;\nprecision highp int;\n";

async function init(options = {}) {
  scene = options.scene || await (await fetch("/api/scene.json")).json();
  vt = new VirtualTexture(gl, scene.pack, { tiles: scene.tiles, ...options });
  await vt.ready;
  window.vt = vt;
  return { slots: [vt.cache.slotsX, vt.cache.slotsY], pinned: vt.cache.pinnedCount, tiles: vt.geometry.tileCount };
}

async function fetchTiles(keys) {
  const out = [], bytes = scene.pack.tile_size ** 2 * 3;
  for (let k = 0; k < keys.length; k += 64) {
    const batch = keys.slice(k, k + 64);
    const r = await fetch(scene.tiles.batch, { method: "POST", body: JSON.stringify({ keys: batch }) });
    if (!r.ok) throw new Error(`batch: HTTP ${r.status}`);
    const body = new Uint8Array(await r.arrayBuffer());
    batch.forEach((_, i) => out.push(body.subarray(i * bytes, (i + 1) * bytes)));
  }
  return out;
}

async function insertTiles(keys) {
  const tiles = await fetchTiles(keys);
  keys.forEach((k, i) => vt.insertTile(vt.geometry.tileIndex(...k), tiles[i]));
  vt.flushTable();
  return vt.cache.resident;
}

const probePrograms = new Map();
// hardware: the sampler's VT_HARDWARE_BILINEAR variant.
function sampleProbes(probes, hardware = false) {
  const n = probes.length / 4, w = Math.min(n, 256), h = Math.ceil(n / 256);
  if (!gl.getExtension("EXT_color_buffer_float")) throw new Error("no EXT_color_buffer_float");
  const fullScreen = "void main() { gl_Position = vec4(vec2(gl_VertexID & 1, gl_VertexID >> 1) * 4.0 - 1.0, 0, 1); }";
  if (!probePrograms.has(hardware)) probePrograms.set(hardware, compile(HEADER + fullScreen,
    HEADER + (hardware ? "#define VT_HARDWARE_BILINEAR\n" : "") + vt.glsl + `
uniform highp sampler2D uProbes;
out vec4 outColor;
void main() {
  vec4 q = texelFetch(uProbes, ivec2(gl_FragCoord.xy), 0);
  outColor = vtSample(int(q.x), q.yz, q.w);
}`));
  const probeProgram = probePrograms.get(hardware);
  const data = new Float32Array(w * h * 4);
  data.set(probes);
  const tex = (format, pixels) => {
    const t = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, t);
    gl.texStorage2D(gl.TEXTURE_2D, 1, format, w, h);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);  // float: not filterable
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    if (pixels) gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, w, h, gl.RGBA, gl.FLOAT, pixels);
    return t;
  };
  const input = tex(gl.RGBA32F, data), target = tex(gl.RGBA32F, null);
  const fb = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
  gl.viewport(0, 0, w, h);
  gl.useProgram(probeProgram);
  vt.bind(probeProgram);
  gl.activeTexture(gl.TEXTURE0);
  gl.bindTexture(gl.TEXTURE_2D, input);
  gl.uniform1i(gl.getUniformLocation(probeProgram, "uProbes"), 0);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const out = new Float32Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, out);  // a test's readback, not the frame path
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  [input, target].forEach((t) => gl.deleteTexture(t));
  gl.deleteFramebuffer(fb);
  return Array.from(out.subarray(0, 4 * n));
}

// Column-major 4 x 4 view-projection of a `render --camera` pose for a display of w x h.
export function viewProjection(camera, w, h) {
  const [ex, ey, ez, tx, ty, tz, fov = 60] = camera;
  const sub = (a, b) => a.map((x, i) => x - b[i]);
  const norm = (a) => { const l = Math.hypot(...a); return a.map((x) => x / l); };
  const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
  const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
  const eye = [ex, ey, ez], f = norm(sub([tx, ty, tz], eye));
  const r = norm(cross(f, [0, 1, 0])), u = cross(r, f);
  const th = Math.tan((fov * Math.PI) / 360), tw = th * w / h, n = 0.01, far = 1000;
  // Rows of projection * view: x' = (r.(p-e)) / tw, y' = (u.(p-e)) / th, w' = f.(p-e).
  const rows = [r.map((x) => x / tw), u.map((x) => x / th), null, f];
  const a = (far + n) / (far - n), b = (-2 * far * n) / (far - n);
  rows[2] = f.map((x) => x * a);
  const m = new Float32Array(16);
  for (let i = 0; i < 4; ++i) {
    const row = rows[i];
    m[i] = row[0]; m[4 + i] = row[1]; m[8 + i] = row[2];
    m[12 + i] = -dot(row, eye) + (i === 2 ? b : 0);
  }
  return m;
}

// The vertex shader of both test passes: a painting's quad with its uv.
const QUAD_VERTEX = HEADER + `
in vec3 aPosition; in vec2 aUv;
uniform mat4 uViewProj;
out vec2 vUv;
void main() { vUv = aUv; gl_Position = uViewProj * vec4(aPosition, 1.0); }`;

let feedbackProgram = null, quads = null;
function drawFeedback(views, placements) {
  feedbackProgram ||= compile(QUAD_VERTEX,
    HEADER + vt.glsl + `
uniform int uPainting;
in vec2 vUv;
out vec4 outColor;
void main() { outColor = vtFeedbackOut(uPainting, vUv); }`);
  for (const v of views) {
    vt.feedback.begin(v.view, v.display[0], v.display[1], v.reduction ?? 8);
    drawQuads(feedbackProgram, v, placements);
    vt.feedback.end(v.view);
  }
}

// One animation frame, as the app's desktop loop ticks (with setTimeout ticks chromium leaves
// some fences unsignalled; feedback.js then reads them late).
const tick = () => new Promise((r) => requestAnimationFrame(() => r()));

// The paintings of a view as the display pass samples them: vtSample at vtLod (the sRGB8
// texel, no light), into an RGBA8 target of the display size; returns its bytes as base64,
// rows bottom up (a test's synchronous readback, not the frame path).
let displayProgram = null;
function render(view, placements) {
  displayProgram ||= compile(QUAD_VERTEX,
    HEADER + vt.glsl + `
uniform int uPainting;
in vec2 vUv;
out vec4 outColor;
void main() { outColor = vtSample(uPainting, vUv, vtLod(uPainting, vUv)); }`);
  quads = null;
  const [w, h] = view.display;
  const target = makeTarget(gl, w, h);  // the app's offscreen target (gl_util.js)
  gl.bindFramebuffer(gl.FRAMEBUFFER, target.framebuffer);
  gl.viewport(0, 0, w, h);
  gl.clearColor(0, 0, 0, 0);
  gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
  drawQuads(displayProgram, view, placements);
  const out = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, out);
  gl.bindFramebuffer(gl.FRAMEBUFFER, null);
  gl.deleteFramebuffer(target.framebuffer);
  gl.deleteTexture(target.texture);
  gl.deleteRenderbuffer(target.depth);
  return base64(out);
}

// Bytes as base64 (a JSON array of a 480 x 360 frame's bytes took seconds to hand over).
function base64(bytes) {
  let text = "";
  for (let i = 0; i < bytes.length; i += 0x8000) text += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(text);
}

// Draws the placements' quads with `program` (uViewProj, uPainting, aPosition, aUv).
function drawQuads(program, v, placements) {
  if (!quads) {
    quads = placements.map((s) => {
      const c = (a, b) => [0, 1, 2].map((i) => s.origin[i] + a * s.u_axis[i] * s.width_m + b * s.v_axis[i] * s.height_m);
      const data = [];
      for (const [a, b] of [[0, 0], [1, 0], [1, 1], [0, 0], [1, 1], [0, 1]]) data.push(...c(a, b), a, b);
      const buffer = gl.createBuffer();
      gl.bindBuffer(gl.ARRAY_BUFFER, buffer);
      gl.bufferData(gl.ARRAY_BUFFER, new Float32Array(data), gl.STATIC_DRAW);
      return { buffer, painting: s.painting };
    });
  }
  const pos = gl.getAttribLocation(program, "aPosition"), uv = gl.getAttribLocation(program, "aUv");
  gl.useProgram(program);
  vt.bind(program);
  gl.uniformMatrix4fv(gl.getUniformLocation(program, "uViewProj"), false,
                      viewProjection(v.camera, v.display[0], v.display[1]));
  gl.disable(gl.CULL_FACE);
  gl.enable(gl.DEPTH_TEST);
  for (const q of quads) {
    gl.bindBuffer(gl.ARRAY_BUFFER, q.buffer);
    gl.enableVertexAttribArray(pos);
    gl.vertexAttribPointer(pos, 3, gl.FLOAT, false, 20, 0);
    gl.enableVertexAttribArray(uv);
    gl.vertexAttribPointer(uv, 2, gl.FLOAT, false, 20, 12);
    gl.uniform1i(gl.getUniformLocation(program, "uPainting"), q.painting);
    gl.drawArrays(gl.TRIANGLES, 0, 6);
  }
}

// Draws the views' feedback passes and waits for each view's readback.
async function readAll(views, placements) {
  while (vt.feedback.pending) { await tick(); vt.feedback.poll(); }  // older readbacks out
  drawFeedback(views, placements);
  const got = new Map();
  for (let k = 0; got.size < views.length && k < 10000; ++k) {
    await tick();
    for (const r of vt.feedback.poll()) got.set(r.view, r);
  }
  return views.map((v) => got.get(v.view));
}

async function feedback(views, placements) {
  quads = null;
  const got = await readAll(views, placements);
  return views.map((v, k) => {
    const r = got[k], keys = {};
    for (const i of new Set(r.keys)) if (i !== 0xFFFFFFFF) keys[i] = vt.geometry.keyOf(i);
    return { view: v.view, width: r.width, height: r.height, keys,
             indices: base64(new Uint8Array(r.keys.buffer, r.keys.byteOffset, r.keys.byteLength)) };
  });
}

// `step`: metres a frame by which every camera (eye and target) moves.
async function benchFeedback(views, placements, frames = 200, step = [0, 0, 0]) {
  quads = null;
  const ms = [], processMs = [], counts = [], pixels = [], uploadMs = [], uploads = [];
  for (let f = 1; f <= frames; ++f) {
    const seen = vt.counters.readbacks;
    vt.beginFrame(f);
    if (vt.counters.uploads > 0) { uploadMs.push(vt.counters.uploadMs); uploads.push(vt.counters.uploads); }
    if (vt.counters.readbacks > seen) {
      ms.push(vt.counters.feedbackMs);
      processMs.push(vt.counters.processMs);
      counts.push(vt.stats().requests);
    }
    const moved = views.map((v) => ({ ...v, camera: v.camera.map((c, i) => (i < 6 ? c + f * step[i % 3] : c)) }));
    drawFeedback(moved, placements);
    await tick();
  }
  for (const t of vt.feedback.views) if (t) pixels.push(t.width * t.height);
  // Then all views' last feedback processed together, `frames` times (new salts): the
  // steady state of a headset, where every view's readback arrives each frame.
  const moved = views.map((v) => ({ ...v, camera: v.camera.map((c, i) => (i < 6 ? c + frames * step[i % 3] : c)) }));
  const buffers = (await readAll(moved, placements)).map((r) => r.keys.slice());
  const together = [], run = 5;  // 5 frames a sample: performance.now() has 0.1 ms steps
  for (let k = 0; k < frames; ++k) {
    const t0 = performance.now();
    for (let j = 1; j <= run; ++j) vt.requests.process(buffers, frames + k * run + j);
    together.push((performance.now() - t0) / run);
  }
  // The baseline in the same run: Barrett's CPU scan, every pixel into a hash set (a JS Set).
  const naive = [];
  for (let k = 0; k < frames; ++k) {
    const t0 = performance.now();
    for (let j = 0; j < run; ++j) {
      const seen = new Set();
      for (const b of buffers) for (let i = 0; i < b.length; ++i) if (b[i] !== 0xFFFFFFFF) seen.add(b[i]);
    }
    naive.push((performance.now() - t0) / run);
  }
  return { ms, processMs, requests: counts, pixels, together, naive, togetherRequests: vt.requests.last.requests,
           uploadMs, uploads, stats: vt.stats() };
}

// The runtime from a cold cache: every frame beginFrame (readbacks -> requests -> fetches ->
// uploads) and the views' feedback passes, until `quiet` frames in a row have nothing missing,
// in flight or waiting (or maxFrames). Returns the frames, the stats and the resident tiles.
async function stream(views, placements, maxFrames = 600, quiet = 5) {
  quads = null;
  let still = 0, f = 0;
  while (f < maxFrames && still < quiet) {
    vt.beginFrame(++f);
    drawFeedback(views, placements);
    await tick();
    const s = vt.stats();
    still = vt.counters.readbacks > 0 && s.commands === 0 && s.inFlight === 0 && s.pending === 0 ? still + 1 : 0;
  }
  const resident = [...vt.cache.slotOf.keys()].map((i) => vt.geometry.keyOf(i));
  return { frames: f, stats: vt.stats(), resident };
}

window.vtTest = { init, insertTiles, sampleProbes, feedback, render, benchFeedback, stream, viewProjection };
window.vtTestReady = true;
