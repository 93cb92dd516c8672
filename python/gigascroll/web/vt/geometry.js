// The pack's geometry as the core's pack/geometry.h defines it, from scene.json's "pack":
// level l of a painting is ceil(W / 2^l) x ceil(H / 2^l) texels in ceil(w_l / P) x
// ceil(h_l / P) tiles of payload P = tile_size - 2 border; its page table is Mp x Np at
// (x, y) in the merged Mc x Nc table; levels below merged_levels() live in the merged table,
// coarser "tail" levels in a small table per painting (cache/page_table.h).
//
// Tiles also get a flat index over all paintings (the core's TileIndex: painting after
// painting, levels 0..l-1 first, row-major inside a level): the feedback pass writes it in
// 32 bits (views/request_processing.h's Vulkan-SVT page index).

export class PaintingInfo {
  constructor(p, tileSize, border, firstIndex) {
    this.index = p.index;
    this.width = p.width;
    this.height = p.height;
    this.payload = tileSize - 2 * border;
    this.levels = p.levels;
    this.tableWidth = p.table_size[0];
    this.tableHeight = p.table_size[1];
    this.tableX = p.table_offset[0];
    this.tableY = p.table_offset[1];
    this.levelWidth = [];
    this.levelHeight = [];
    this.tilesX = [];
    this.tilesY = [];
    this.levelFirst = [];   // flat index of tile (0, 0) of level l
    let first = firstIndex;
    for (let l = 0; l < this.levels; ++l) {
      const w = Math.ceil(this.width / 2 ** l), h = Math.ceil(this.height / 2 ** l);
      const tx = Math.ceil(w / this.payload), ty = Math.ceil(h / this.payload);
      checkLevel(p, l, w, h, tx, ty);
      this.levelWidth.push(w);
      this.levelHeight.push(h);
      this.tilesX.push(tx);
      this.tilesY.push(ty);
      this.levelFirst.push(first);
      first += tx * ty;
    }
    const last = this.levels - 1;
    if (this.levelWidth[last] > this.payload || this.levelHeight[last] > this.payload ||
        (last > 0 && this.levelWidth[last - 1] <= this.payload && this.levelHeight[last - 1] <= this.payload) ||
        this.tableWidth < this.tilesX[0] || this.tableHeight < this.tilesY[0])
      throw new Error(`pack: painting ${p.index}'s levels or page table are not the core's geometry`);
    this.firstIndex = firstIndex;
    this.endIndex = first;
    // countr_zero(min(Mp, Np)) + 1, at most the level count (PaintingGeometry::merged_levels).
    const fit = Math.log2(Math.min(this.tableWidth, this.tableHeight)) + 1;
    this.mergedLevels = Math.min(fit, this.levels);
  }
  // Entry grid of level l: the painting's table block for merged levels, else the tile grid.
  gridWidth(l) { return l < this.mergedLevels ? this.tableWidth >> l : this.tilesX[l]; }
  gridHeight(l) { return l < this.mergedLevels ? this.tableHeight >> l : this.tilesY[l]; }
}

// scene.json's sizes must be the ones the core's formula gives (a mismatch would make the
// sampler read the wrong tiles).
function checkLevel(p, l, w, h, tx, ty) {
  const s = p.level_sizes && p.level_sizes[l], t = p.level_tiles && p.level_tiles[l];
  if ((s && (s[0] !== w || s[1] !== h)) || (t && (t[0] !== tx || t[1] !== ty)))
    throw new Error(`pack: painting ${p.index} level ${l} is not the core's geometry`);
}

// What the runtime relies on (PackGeometry::validate): a clear Error for a bad description.
function checkPack(pack) {
  const int = (x) => Number.isInteger(x) && x >= 0;
  const pow2 = (x) => int(x) && x > 0 && (x & (x - 1)) === 0;
  if (!pack || !int(pack.tile_size) || !int(pack.border) || pack.border < 1 || pack.tile_size <= 2 * pack.border)
    throw new Error("pack: tile_size must exceed 2 * border, border >= 1");
  if (!Array.isArray(pack.table_size) || !pack.table_size.every(pow2))
    throw new Error("pack: table_size must be two powers of two");
  if (!Array.isArray(pack.paintings) || pack.paintings.length === 0) throw new Error("pack: no paintings");
  pack.paintings.forEach((p, i) => {
    const ok = p && p.index === i && int(p.width) && int(p.height) && p.width > 0 && p.height > 0 &&
      int(p.levels) && p.levels >= 1 && p.levels <= 32 &&
      Array.isArray(p.table_size) && p.table_size.every(pow2) &&
      Array.isArray(p.table_offset) && p.table_offset.every(int) &&
      p.table_offset[0] % p.table_size[0] === 0 && p.table_offset[1] % p.table_size[1] === 0 &&
      p.table_offset[0] + p.table_size[0] <= pack.table_size[0] &&
      p.table_offset[1] + p.table_size[1] <= pack.table_size[1];
    if (!ok) throw new Error(`pack: painting ${i} is not a valid placement in the merged page table`);
  });
}

export class PackGeometry {
  constructor(pack) {
    checkPack(pack);
    this.tileSize = pack.tile_size;
    this.border = pack.border;
    this.payload = pack.tile_size - 2 * pack.border;
    this.tableWidth = pack.table_size[0];
    this.tableHeight = pack.table_size[1];
    this.hash = pack.hash;
    this.paintings = [];
    let first = 0;
    for (const p of pack.paintings) {
      const info = new PaintingInfo(p, this.tileSize, this.border, first);
      this.paintings.push(info);
      first = info.endIndex;
    }
    this.tileCount = first;
    if (first >= 0xFFFFFFFF) throw new Error("pack: too many tiles for 32-bit feedback indices");
    this.mergedLevels = Math.max(...this.paintings.map((p) => p.mergedLevels));
  }

  // Flat index of tile (p, l, tx, ty).
  tileIndex(p, l, tx, ty) {
    const q = this.paintings[p];
    return q.levelFirst[l] + ty * q.tilesX[l] + tx;
  }

  // The tile key [p, l, tx, ty] of a flat index; null outside the pack.
  keyOf(index) {
    const k = [0, 0, 0, 0];
    return this.keyInto(index, k) ? k : null;
  }

  // The same into out[0..3] (no allocation); false outside the pack. A binary search over
  // the paintings, then the levels from the finest.
  keyInto(index, out) {
    const ps = this.paintings;
    let lo = 0, hi = ps.length - 1;
    if (!(index >= 0 && index < this.tileCount)) return false;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (ps[mid].firstIndex <= index) lo = mid; else hi = mid - 1;
    }
    const q = ps[lo];
    let l = q.levels - 1;
    while (q.levelFirst[l] > index) --l;
    const r = index - q.levelFirst[l];
    out[0] = lo; out[1] = l; out[2] = r % q.tilesX[l]; out[3] = Math.floor(r / q.tilesX[l]);
    return true;
  }

  // Every pinned tile in the core's order (cache/virtual_texture.cpp): per painting, the
  // levels from min(merged_levels, levels - 1) up, rows, columns.
  pinnedTiles() {
    const out = [];
    for (let p = 0; p < this.paintings.length; ++p) {
      const q = this.paintings[p];
      for (let l = Math.min(q.mergedLevels, q.levels - 1); l < q.levels; ++l)
        for (let y = 0; y < q.tilesY[l]; ++y)
          for (let x = 0; x < q.tilesX[l]; ++x) out.push([p, l, x, y]);
    }
    return out;
  }

  isPinned(p, l) {
    const q = this.paintings[p];
    return l >= Math.min(q.mergedLevels, q.levels - 1);
  }
}
