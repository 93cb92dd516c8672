// The virtual texture on the GPU: the facade the client's app uses (the virtual texturing
// paper's runtime, seed 000 §4: tile determination -> request processing -> loading ->
// physical texture and page-table update -> display), mirroring the C++ core's arithmetic.
//
//   const vt = new VirtualTexture(gl, scene.pack, {tiles: scene.tiles, budgetBytes, ...});
//                                   // (tiles: scene.json's "tiles"; by default the batch URL
//                                   // /api/tiles/{pack.hash}/batch, 64 keys a batch)
//   await vt.ready;                 // every painting's coarse tail resident: no pixel is black
//   vt.glsl                         // GLSL ES 3.00 to paste after "#version 300 es" and the
//                                   // precision lines of any shader that samples or writes
//                                   // feedback; it declares:
//       vec4  vtSample(int painting, vec2 uv, float lod)  // sRGB8 texel as 0..1 (not
//             // linearised), trilinear between floor(lod) and floor(lod)+1 through the page
//             // table with the finest-resident fallback (eqs 5-10), clamp to edge
//       float vtLod(int painting, vec2 uv)   // lambda = log2(texels per display pixel) from
//             // the uv derivatives, the OpenGL rule the core's feedback pass uses
//       vec4  vtFeedbackOut(int painting, vec2 uv)  // the feedback pass's output colour
//   vt.bind(program)                // sets its textures and uniforms on a program using vt.glsl
//                                   // (call after gl.useProgram; it uses texture units
//                                   // vt.firstUnit .. vt.firstUnit + 3)
//   vt.beginFrame(frameNumber)      // once a frame before drawing: polls the feedback
//                                   // readbacks, turns them into requests (the paper's hash
//                                   // with the frame salt), issues fetches, uploads arrived
//                                   // tiles within the budget, updates the page table texture
//   vt.feedback.begin(view, displayWidth, displayHeight, reduction)
//                                   // binds view's feedback target (view 0, 1: eyes, 2: the
//                                   // magnifier; reduction 8 for eyes, 1 for the magnifier:
//                                   // the size is max(1, floor(display / reduction))), sets
//                                   // the viewport and clears it to "no request"
//   ... draw the paintings with a shader whose output is vtFeedbackOut(painting, uv) ...
//   vt.feedback.end(view)           // starts the asynchronous readback (pixel-pack buffer +
//                                   // fence; never a synchronous readPixels)
//   vt.stats()                      // {requests, commands, inFlight, uploads, hitRate,
//                                   //  feedbackMs, resident, pending, frame}
//   vt.dispose()
//
// Test hooks (tests/python/test_web_vt.py): vt.insertTile(key, rgbBytes) inserts a tile
// directly; vt.cache, vt.pageTable, vt.requests expose the parts.
import { PackGeometry } from "./geometry.js";
import { PageTable } from "./page_table.js";
import { TileCache } from "./cache.js";
import { FeedbackPass } from "./feedback.js";
import { RequestProcessor } from "./requests.js";
import { TileLoader } from "./loader.js";
import { samplerGlsl } from "./sampler.glsl.js";

export const DEFAULTS = {
  budgetBytes: 64 << 20,      // physical texture memory (RGBA8 estimate per texel)
  maxRequestsPerFrame: 16,    // N of the paper's capped direct loading
  maxUploadsPerFrame: 16,     // texSubImage2D tiles a frame
  maxBatchesInFlight: 4,      // POSTs of at most tiles.max_batch keys each
  tableBits: 16,              // the request hash table: 2^16 slots
  firstUnit: 8,               // texture units firstUnit .. firstUnit + 3
};

export class VirtualTexture {
  constructor(gl, pack, options = {}) {
    throw new Error("VirtualTexture: not implemented yet");
  }
  get glsl() { return ""; }
  bind(program) {}
  beginFrame(frameNumber) {}
  stats() { return {}; }
  dispose() {}
}
