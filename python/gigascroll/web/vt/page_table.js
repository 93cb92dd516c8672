// The mip-mapped page table (the virtual texturing paper §4.3; the core's cache/page_table.*):
// entry (painting p, level l, tile x, y) names the finest resident tile covering that tile,
// as level << 24 | slot, so the sampler's "try l, l + 1, ..." fallback is one read. Level l
// of the merged table is (Mc >> l) x (Nc >> l) entries, painting p's block at its offset >> l,
// for l < its merged levels; coarser tail levels live in a per-painting grid of its real
// tiles. Inserting a tile rewrites the entries it covers that pointed at something coarser;
// evicting one rewrites those that pointed at it with its parent's entry (the core's
// incremental update, entry for entry).
//
// On the GPU: an R32UI texture whose mip level l is the merged table's level l (texelFetch
// at that level), an R32UI atlas of every painting's tail levels, and an RGBA32UI info texture:
// texel (l, p) = (x, y of the painting's level-l grid origin, 0 merged / 1 tail, flat index
// of the level's first tile), texel (32, p) = (width, height, levels, 0). Only the
// rectangles of each level that changed since the last upload are sent (texSubImage2D).

export const NONE = 0xFFFFFFFF;
export const INFO_COLUMNS = 33;

export function entryLevel(e) { return e >>> 24; }
export function entrySlot(e) { return e & 0xFFFFFF; }

// Rectangles a grid keeps before it uploads their bounding box instead (a frame's 16 inserts
// and their evictions touch at most 32 a level).
const MAX_RECTS = 64;

class Grid {  // one level of the merged table or the tail atlas, with its changed rectangles
  constructor(width, height) {
    this.width = width;
    this.height = height;
    this.data = new Uint32Array(width * height).fill(NONE);
    this.clean();
  }
  clean() {
    this.rects = [];
    this.x0 = this.y0 = Infinity;
    this.x1 = this.y1 = -Infinity;
  }
  touch(x0, y0, x1, y1) {  // [x0, x1) x [y0, y1) changed
    if (this.rects.length < MAX_RECTS) this.rects.push([x0, y0, x1, y1]);
    this.x0 = Math.min(this.x0, x0); this.y0 = Math.min(this.y0, y0);
    this.x1 = Math.max(this.x1, x1); this.y1 = Math.max(this.y1, y1);
  }
  get dirty() { return this.x1 > this.x0; }
  // What to upload: each rectangle, or their bounding box when there were too many (scattered
  // tiles' bounding box can be most of a level: megabytes a frame instead of kilobytes).
  uploads() {
    if (!this.dirty) return [];
    if (this.rects.length >= MAX_RECTS) return [[this.x0, this.y0, this.x1, this.y1]];
    return this.rects;
  }
}

export class PageTable {
  constructor(geometry) {
    this.geometry = geometry;
    this.merged = [];
    for (let l = 0; l < geometry.mergedLevels; ++l)
      this.merged.push(new Grid(geometry.tableWidth >> l, geometry.tableHeight >> l));
    // Tail atlas: every (painting, tail level) grid in its own band of rows at x = 0.
    const bands = [];
    let rows = 0, cols = 1;
    for (const q of geometry.paintings)
      for (let l = q.mergedLevels; l < q.levels; ++l) {
        bands.push([q.index, l, rows]);
        rows += q.tilesY[l];
        cols = Math.max(cols, q.tilesX[l]);
      }
    this.tail = new Grid(cols, Math.max(rows, 1));
    // views[p][l] = {grid, x, y}: where entry (0, 0) of the level's grid lies.
    this.views = geometry.paintings.map((q) => {
      const v = [];
      for (let l = 0; l < q.mergedLevels; ++l)
        v.push({ grid: this.merged[l], x: q.tableX >> l, y: q.tableY >> l, tail: 0 });
      return v;
    });
    for (const [p, l, y] of bands) this.views[p][l] = { grid: this.tail, x: 0, y, tail: 1 };
  }

  lookup(p, l, x, y) {
    const v = this.views[p][l];
    return v.grid.data[(v.y + y) * v.grid.width + v.x + x];
  }

  // Calls f(data, index) for every entry of levels <= key's level under key's tile, then marks
  // the rectangles dirty (PageTable::for_each_covered).
  forEachCovered(p, level, tx, ty, f) {
    const q = this.geometry.paintings[p];
    for (let k = level; k >= 0; --k) {
      const s = level - k, v = this.views[p][k], g = v.grid;
      const x0 = tx << s, y0 = ty << s;
      const x1 = Math.min((tx + 1) << s, q.gridWidth(k)), y1 = Math.min((ty + 1) << s, q.gridHeight(k));
      for (let y = y0; y < y1; ++y) {
        const row = (v.y + y) * g.width + v.x;
        for (let x = x0; x < x1; ++x) f(g.data, row + x);
      }
      if (x1 > x0 && y1 > y0) g.touch(v.x + x0, v.y + y0, v.x + x1, v.y + y1);
    }
  }

  insert(p, l, tx, ty, slot) {
    const e = ((l << 24) | slot) >>> 0;
    this.forEachCovered(p, l, tx, ty, (d, i) => {
      const x = d[i];
      if (x === NONE || x >>> 24 >= l) d[i] = e;
    });
  }

  evict(p, l, tx, ty) {
    const q = this.geometry.paintings[p];
    const parent = l + 1 < q.levels ? this.lookup(p, l + 1, tx >> 1, ty >> 1) : NONE;
    this.forEachCovered(p, l, tx, ty, (d, i) => {
      const x = d[i];
      if (x !== NONE && x >>> 24 === l) d[i] = parent;
    });
  }

  // The GPU side: creates the textures (once) and uploads every dirty rectangle.
  upload(gl) {
    if (!this.tableTexture) this.createTextures(gl);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
    let entries = 0;
    const send = (texture, level, g) => {
      if (!g.dirty) return;
      gl.bindTexture(gl.TEXTURE_2D, texture);
      gl.pixelStorei(gl.UNPACK_ROW_LENGTH, g.width);
      for (const [x0, y0, x1, y1] of g.uploads()) {
        gl.texSubImage2D(gl.TEXTURE_2D, level, x0, y0, x1 - x0, y1 - y0, gl.RED_INTEGER,
                         gl.UNSIGNED_INT, g.data, y0 * g.width + x0);
        entries += (x1 - x0) * (y1 - y0);
      }
      g.clean();
    };
    this.merged.forEach((g, l) => send(this.tableTexture, l, g));
    send(this.tailTexture, 0, this.tail);
    gl.pixelStorei(gl.UNPACK_ROW_LENGTH, 0);
    gl.bindTexture(gl.TEXTURE_2D, null);
    this.uploadedEntries = entries;  // this call's, for stats
  }

  createTextures(gl) {
    const max = gl.getParameter(gl.MAX_TEXTURE_SIZE), geo = this.geometry;
    if (geo.tableWidth > max || geo.tableHeight > max || this.tail.width > max || this.tail.height > max ||
        geo.paintings.length > max)
      throw new Error(`page table ${geo.tableWidth} x ${geo.tableHeight} (tails ${this.tail.width} x ` +
                      `${this.tail.height}, ${geo.paintings.length} paintings) exceeds MAX_TEXTURE_SIZE ${max}`);
    const make = (levels, w, h, format) => {
      const t = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, t);
      gl.texStorage2D(gl.TEXTURE_2D, levels, format, w, h);
      // Integer textures are complete only with NEAREST filters; the mipmapped one lets
      // texelFetch read every level.
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, levels > 1 ? gl.NEAREST_MIPMAP_NEAREST : gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAX_LEVEL, levels - 1);
      return t;
    };
    this.tableTexture = make(Math.max(1, geo.mergedLevels), geo.tableWidth, geo.tableHeight, gl.R32UI);
    this.tailTexture = make(1, this.tail.width, this.tail.height, gl.R32UI);
    this.merged.forEach((g) => g.touch(0, 0, g.width, g.height));
    this.tail.touch(0, 0, this.tail.width, this.tail.height);
    const n = geo.paintings.length;
    this.infoTexture = make(1, INFO_COLUMNS, n, gl.RGBA32UI);
    const info = new Uint32Array(INFO_COLUMNS * n * 4);
    geo.paintings.forEach((q, p) => {
      for (let l = 0; l < q.levels; ++l) {
        const v = this.views[p][l], o = 4 * (p * INFO_COLUMNS + l);
        info.set([v.x, v.y, v.tail, q.levelFirst[l]], o);
      }
      info.set([q.width, q.height, q.levels, 0], 4 * (p * INFO_COLUMNS + 32));
    });
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
    gl.texSubImage2D(gl.TEXTURE_2D, 0, 0, 0, INFO_COLUMNS, n, gl.RGBA_INTEGER, gl.UNSIGNED_INT, info);
  }

  dispose(gl) {
    for (const t of [this.tableTexture, this.tailTexture, this.infoTexture]) if (t) gl.deleteTexture(t);
    this.tableTexture = this.tailTexture = this.infoTexture = null;
  }
}
