// The physical texture (the virtual texturing paper §4.3; the core's cache/virtual_texture.*):
// a grid of slots_x x slots_y tile slots of tile_size texels (border included) in one RGB8
// texture, LRU replacement over the unpinned slots, every tile of each painting's tail
// levels pinned in slots 0.. in the core's order, free slots handed out lowest first. Tiles
// are named by their flat index (geometry.js). Inserting into a full cache evicts the least
// recently used tile and updates the page table, as VirtualTexture::insert does.

import { NONE } from "./page_table.js";

const NIL = -1;

// Slots from MAX_TEXTURE_SIZE and a memory budget (counted as RGBA8: drivers pad RGB8).
export function slotGrid(maxTextureSize, tileSize, budgetBytes, pinned) {
  const perAxis = Math.floor(maxTextureSize / tileSize);
  const budgetSlots = Math.max(pinned + 1, Math.floor(budgetBytes / (tileSize * tileSize * 4)));
  const sx = Math.min(perAxis, Math.ceil(Math.sqrt(budgetSlots)));
  const sy = Math.min(perAxis, Math.ceil(budgetSlots / sx));
  if (sx * sy <= pinned)
    throw new Error(`the physical texture (${sx} x ${sy} slots) cannot hold the ${pinned} pinned tiles`);
  return [sx, sy];
}

export class TileCache {
  constructor(geometry, pageTable, slotsX, slotsY) {
    const n = slotsX * slotsY;
    if (!(n >= 2 && n < 2 ** 24)) throw new Error("slots must be at least 2 and fewer than 2^24");
    this.geometry = geometry;
    this.pageTable = pageTable;
    this.slotsX = slotsX;
    this.slotsY = slotsY;
    this.slotOf = new Map();                 // flat index -> slot
    this.keyOf = new Uint32Array(n).fill(NONE);
    this.pinned = new Uint8Array(n);
    this.prev = new Int32Array(n).fill(NIL);
    this.next = new Int32Array(n).fill(NIL);
    this.head = NIL;                         // most recently used
    this.tail = NIL;
    const pins = geometry.pinnedTiles();
    if (pins.length >= n) throw new Error(`${n} slots cannot hold the ${pins.length} pinned tiles plus one`);
    this.pinnedKeys = pins;
    this.pinnedSlot = new Map(pins.map((k, i) => [geometry.tileIndex(...k), i]));
    this.pinnedCount = pins.length;
    this.free = [];
    for (let s = n - 1; s >= pins.length; --s) this.free.push(s);
    this.stats = { insertions: 0, evictions: 0, hits: 0, misses: 0 };
  }

  get slots() { return this.slotsX * this.slotsY; }
  get resident() { return this.slotOf.size; }
  isResident(index) { return this.slotOf.has(index); }

  unlink(s) {
    const p = this.prev[s], q = this.next[s];
    if (p === NIL) this.head = q; else this.next[p] = q;
    if (q === NIL) this.tail = p; else this.prev[q] = p;
    this.prev[s] = this.next[s] = NIL;
  }
  pushFront(s) {
    this.prev[s] = NIL;
    this.next[s] = this.head;
    if (this.head === NIL) this.tail = s; else this.prev[this.head] = s;
    this.head = s;
  }
  touch(s) {
    if (this.pinned[s]) return;
    this.unlink(s);
    this.pushFront(s);
  }

  // A request for a tile: a hit makes it most recently used; returns whether it is resident.
  request(index) {
    const s = this.slotOf.get(index);
    if (s === undefined) { ++this.stats.misses; return false; }
    ++this.stats.hits;
    this.touch(s);
    return true;
  }

  // Where tile `index` goes: its slot (-1 if already resident; it is then touched) after
  // evicting the LRU tile when no slot is free; the page table is updated. The caller
  // uploads the texels to slot's rectangle (TileCache.upload).
  place(index, pin = false) {
    const have = this.slotOf.get(index);
    if (have !== undefined) { this.touch(have); return -1; }
    const key = this.geometry.keyOf(index);
    if (!key) throw new Error(`tile index ${index} is outside the pack`);
    let s;
    if (pin) {
      s = this.pinnedSlot.get(index);
      if (s === undefined) throw new Error(`tile ${key} is not a pinned tile`);
      this.pinned[s] = 1;
    } else if (this.free.length) {
      s = this.free.pop();
    } else {
      s = this.tail;
      if (s === NIL) throw new Error("no slot to evict");
      this.unlink(s);
      const old = this.keyOf[s];
      this.slotOf.delete(old);
      this.pageTable.evict(...this.geometry.keyOf(old));
      ++this.stats.evictions;
    }
    this.keyOf[s] = index;
    this.slotOf.set(index, s);
    this.pageTable.insert(key[0], key[1], key[2], key[3], s);
    if (!pin) this.pushFront(s);
    ++this.stats.insertions;
    return s;
  }

  createTexture(gl) {
    const T = this.geometry.tileSize;
    this.texture = gl.createTexture();
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    gl.texStorage2D(gl.TEXTURE_2D, 1, gl.RGB8, this.slotsX * T, this.slotsY * T);
    // Linear for the sampler's hardware-bilinear option; texelFetch ignores the filter.
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.LINEAR);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_S, gl.CLAMP_TO_EDGE);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_WRAP_T, gl.CLAMP_TO_EDGE);
    gl.bindTexture(gl.TEXTURE_2D, null);
  }

  // Copies a tile's T x T RGB8 texels (rows top to bottom, as the server sends them) into
  // slot s of the physical texture (row 0 of the texture is the tile's first row).
  upload(gl, s, rgb) {
    if (!this.texture) this.createTexture(gl);
    const T = this.geometry.tileSize;
    if (rgb.length !== T * T * 3) throw new Error(`a tile is ${T * T * 3} bytes, got ${rgb.length}`);
    gl.bindTexture(gl.TEXTURE_2D, this.texture);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 1);
    gl.texSubImage2D(gl.TEXTURE_2D, 0, (s % this.slotsX) * T, Math.floor(s / this.slotsX) * T, T, T,
                     gl.RGB, gl.UNSIGNED_BYTE, rgb);
    gl.pixelStorei(gl.UNPACK_ALIGNMENT, 4);
    gl.bindTexture(gl.TEXTURE_2D, null);
  }

  dispose(gl) {
    if (this.texture) gl.deleteTexture(this.texture);
    this.texture = null;
  }
}
