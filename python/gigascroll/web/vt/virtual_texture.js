// The virtual texture on the GPU: the facade the client's app uses (the virtual texturing
// paper's runtime, VT-mobile-VR §4: tile determination -> request processing -> loading ->
// physical texture and page-table update -> display), mirroring the C++ core's arithmetic.
//
//   const vt = new VirtualTexture(gl, scene.pack, {tiles: scene.tiles, budgetBytes, ...});
//                                   // (tiles: scene.json's "tiles"; by default the batch URL
//                                   // /api/tiles/{pack.hash}/batch, 64 keys a batch)
//   await vt.ready;                 // every painting's coarse tail resident: no pixel is black
//                                   // (rejects with the server's answer if they cannot load;
//                                   // beginFrame does nothing before)
//   vt.glsl                         // GLSL ES 3.00 to paste after "#version 300 es" and the
//                                   // precision lines of any shader that samples or writes
//                                   // feedback; it declares:
//       vec4  vtSample(int painting, vec2 uv, float lod)  // sRGB8 texel as 0..1 (not
//             // linearised), trilinear between floor(lod) and floor(lod)+1 through the page
//             // table with the finest-resident fallback (eqs 5-10), clamp to edge
//       float vtLod(int painting, vec2 uv)   // lambda = log2(texels per display pixel) from
//             // the uv derivatives, the OpenGL rule the core's feedback pass uses
//       vec4  vtFeedbackOut(int painting, vec2 uv)  // the feedback pass's output colour
//             // (the requested tile's 32-bit flat index as RGBA8; call it unconditionally:
//             // it takes derivatives)
//       vec4  vtFeedbackNone()               // what surfaces other than paintings write
//   vt.bind(program)                // sets its textures and uniforms on a program using vt.glsl
//                                   // (call after gl.useProgram, and after feedback.begin in
//                                   // a feedback pass: it sets the pass's pixel scale; it
//                                   // uses texture units vt.firstUnit .. vt.firstUnit + 3)
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
//                                   //  feedbackMs, processMs, resident, pending, frame,
//                                   //  readbackFrame (the frame the newest processed
//                                   //  feedback was drawn in), ...}
//   vt.dispose()
//
// Options also take slots: [x, y] (the physical texture's grid instead of the budget's) and
// useWorker: false (fetch on the main thread). The page table is R32UI entries holding the
// core's PageEntry bits verbatim (level << 24 | slot). Test hooks (tests/python/
// test_web_vt.py, web/vt/test/harness.js): vt.insertTile(index, rgbBytes) inserts a tile
// directly; vt.geometry, vt.cache, vt.pageTable, vt.requests, vt.loader expose the parts.
import { PackGeometry } from "./geometry.js";
import { PageTable } from "./page_table.js";
import { TileCache, slotGrid } from "./cache.js";
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
  hardwareBilinear: false,    // one filtered fetch a level instead of four texelFetch
};

// The sampler's uniforms: its four textures in unit order, then its two parameters.
const UNIFORMS = ["uVtTable", "uVtTail", "uVtInfo", "uVtPhysical", "uVtTile", "uVtPixelScale"];

export class VirtualTexture {
  constructor(gl, pack, options = {}) {
    const o = { ...DEFAULTS, ...options };
    this.gl = gl;
    this.options = o;
    this.geometry = new PackGeometry(pack);
    this.pageTable = new PageTable(this.geometry);
    const pins = this.geometry.pinnedTiles();
    const [sx, sy] = o.slots || slotGrid(gl.getParameter(gl.MAX_TEXTURE_SIZE), this.geometry.tileSize,
                                         o.budgetBytes, pins.length);
    this.cache = new TileCache(this.geometry, this.pageTable, sx, sy);
    this.cache.createTexture(gl);
    this.requests = new RequestProcessor(this.geometry, this.cache, this.pageTable,
                                         { tableBits: o.tableBits, perFrame: o.maxRequestsPerFrame });
    this.loader = new TileLoader(this.geometry, o.tiles, { maxBatchesInFlight: o.maxBatchesInFlight,
                                                           useWorker: o.useWorker !== false });
    this.feedback = new FeedbackPass(gl);
    this.firstUnit = o.firstUnit;
    this.locations = new WeakMap();
    this.frame = 0;
    this.isReady = false;
    this.counters = { uploads: 0, uploadMs: 0, feedbackMs: 0, processMs: 0, readbacks: 0,
                      readbackFrame: -1, failed: 0 };
    this.pageTable.upload(gl);
    this.ready = this.loadPinned(pins);
  }

  get glsl() { return (this.options.hardwareBilinear ? "#define VT_HARDWARE_BILINEAR\n" : "") + samplerGlsl; }

  // Fetches and uploads every pinned tile (no budget: nothing is drawn before they are in).
  async loadPinned(pins) {
    const want = new Set(pins.map((k) => this.geometry.tileIndex(...k)));
    this.loader.request([...want]);
    while (want.size) {
      await new Promise((r) => setTimeout(r, 5));
      const failed = this.loader.takeFailed();
      if (failed.length) throw new Error(`pinned tiles failed to load: ${failed[0].error}`);
      for (const t of this.loader.take(Infinity)) {
        if (!want.delete(t.index)) { this.loader.arrived.push(t); continue; }
        this.cache.upload(this.gl, this.cache.place(t.index, true), t.bytes);
      }
    }
    this.pageTable.upload(this.gl);
    this.isReady = true;
    return this;
  }

  // Inserts a tile at once (tests; the pinned ones go to their slots): the page table is
  // uploaded at the next beginFrame or flushTable.
  insertTile(index, rgb) {
    const key = this.geometry.keyOf(index);
    if (!key) throw new Error(`tile index ${index} is outside the pack`);
    const s = this.cache.place(index, this.geometry.isPinned(key[0], key[1]));
    if (s >= 0) this.cache.upload(this.gl, s, rgb);
    return s;
  }
  flushTable() { this.pageTable.upload(this.gl); }

  // The frame's work before drawing (the paper's five stages less the display); nothing
  // before vt.ready (the pinned tiles must reach their pinned slots first).
  beginFrame(frameNumber = this.frame + 1) {
    if (!this.isReady) return;
    this.frame = frameNumber;
    this.feedback.frame = frameNumber;
    const t0 = performance.now();
    const readbacks = this.feedback.poll();
    const t1 = performance.now();
    if (readbacks.length) {
      this.requests.process(readbacks.map((r) => r.keys), frameNumber);
      ++this.counters.readbacks;
      this.counters.readbackFrame = Math.max(...readbacks.map((r) => r.frame));
    }
    const t2 = performance.now();
    this.counters.feedbackMs = t2 - t0;
    this.counters.processMs = t2 - t1;
    this.upload();
    const room = Math.max(0, this.loader.maxBatch * this.options.maxBatchesInFlight - this.loader.tilesInFlight);
    this.loader.request(this.requests.issue(room));
  }

  // Uploads arrived tiles within the per-frame budget and the page table's changes.
  upload() {
    const t0 = performance.now();
    for (const f of this.loader.takeFailed()) {
      this.counters.failed += f.indices.length;
      for (const i of f.indices) this.requests.arrived(i);
    }
    const tiles = this.loader.take(this.options.maxUploadsPerFrame);
    for (const t of tiles) {
      this.requests.arrived(t.index);
      const s = this.cache.place(t.index);
      if (s >= 0) this.cache.upload(this.gl, s, t.bytes);
    }
    this.counters.uploads = tiles.length;
    this.pageTable.upload(this.gl);
    this.counters.uploadMs = performance.now() - t0;
  }

  // Sets the textures (units firstUnit .. firstUnit + 3) and uniforms of a program that
  // uses vt.glsl; the program must be in use. Between feedback.begin and end it also sets
  // the feedback target's pixel scale, so call it after begin.
  bind(program) {
    const gl = this.gl, u = this.firstUnit, pt = this.pageTable;
    let at = this.locations.get(program);  // uniform locations, looked up once a program
    if (!at) {
      at = Object.fromEntries(UNIFORMS.map((name) => [name, gl.getUniformLocation(program, name)]));
      this.locations.set(program, at);
    }
    const textures = [pt.tableTexture, pt.tailTexture, pt.infoTexture, this.cache.texture];
    textures.forEach((texture, k) => {
      gl.activeTexture(gl.TEXTURE0 + u + k);
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.uniform1i(at[UNIFORMS[k]], u + k);
    });
    gl.activeTexture(gl.TEXTURE0);
    const g = this.geometry;
    gl.uniform4i(at.uVtTile, g.tileSize, g.border, g.payload, this.cache.slotsX);
    gl.uniform2f(at.uVtPixelScale, ...this.feedback.pixelScale);
  }

  stats() {
    const r = this.requests.last, c = this.cache.stats;
    return {
      frame: this.frame,
      requests: r.requests,
      commands: r.commands,
      collisions: r.collisions,
      hitRate: r.requests ? r.hits / r.requests : 1,
      cacheHitRate: c.hits + c.misses ? c.hits / (c.hits + c.misses) : 1,
      inFlight: this.loader.tilesInFlight,
      pending: this.requests.pending.length + this.loader.arrived.length,
      uploads: this.counters.uploads,
      tableEntriesUploaded: this.pageTable.uploadedEntries,
      uploadMs: this.counters.uploadMs,       // JS time of the tiles' and page table's uploads
      feedbackMs: this.counters.feedbackMs,   // readback copies + processing, this frame
      processMs: this.counters.processMs,     // processing alone
      readbacks: this.counters.readbacks,     // frames that processed a readback
      readbackFrame: this.counters.readbackFrame,  // the newest processed readback's frame
      resident: this.cache.resident,
      slots: this.cache.slots,
      evictions: c.evictions,
      failed: this.counters.failed,
      bytesReceived: this.loader.bytesReceived,
      skippedReadbacks: this.feedback.skipped,
      lateReadbacks: this.feedback.late,      // read LATE_FRAMES after drawing, unsignalled
    };
  }

  dispose() {
    this.loader.dispose();
    this.feedback.dispose();
    this.pageTable.dispose(this.gl);
    this.cache.dispose(this.gl);
  }
}
