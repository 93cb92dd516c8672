// Request processing (the virtual texturing paper §4.2.1; the core's views/request_hash.* and
// views/request_processing.*): the frame's feedback readbacks, all views together, into the
// set of distinct requests, their responses (the finest resident tile covering each) and the
// load commands (requests whose response is not the request), then the paper's capped direct
// loading (loading/load_strategy.*): at most N commands a frame, finest first, the rest
// issued on the next frames until a new command set replaces them, never a tile in flight.
//
// The result table is the paper's hash (eqs 1, 2) as the core widens it: B = p 2^37 + l 2^32 +
// morton(x, y), F = frame + 2^20 + 1, slot = top k bits of a (B F) mod 2^64 with L'Ecuyer's
// a = 2862933555777941757; on a collision the smaller level wins (ties: the smaller key),
// the other request is lost for this frame and comes back in a later one under another salt.
// 64-bit products are done on 16-bit limbs (exact in doubles), only for the few keys that pass
// the repeat filter (the previous pixel's key and a 256-entry cache of recent keys, the
// core's RepeatFilter), so the per-pixel loop is a comparison.

import { NONE } from "./page_table.js";

const A_HI = 0x27bb2ee6, A_LO = 0x87b0b0fd;  // 2862933555777941757
export const FRAME_OFFSET = 2 ** 20 + 1;

// Low 64 bits of (ah 2^32 + al)(bh 2^32 + bl), as [hi, lo] uint32.
export function mul64(ah, al, bh, bl) {
  const a0 = al & 0xffff, a1 = al >>> 16, b0 = bl & 0xffff, b1 = bl >>> 16;
  const p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  const mid = (p00 >>> 16) + (p01 & 0xffff) + (p10 & 0xffff);
  const lo = (((mid & 0xffff) << 16) | (p00 & 0xffff)) >>> 0;
  const hi = (p11 + Math.floor(p01 / 65536) + Math.floor(p10 / 65536) + Math.floor(mid / 65536) +
              Math.imul(ah, bl) + Math.imul(al, bh)) >>> 0;
  return [hi, lo];
}

// morton2: x in the even bits, y in the odd bits (16 bits each).
export function morton2(x, y) {
  const spread = (v) => {
    v &= 0xffff;
    v = (v | (v << 8)) & 0x00ff00ff;
    v = (v | (v << 4)) & 0x0f0f0f0f;
    v = (v | (v << 2)) & 0x33333333;
    v = (v | (v << 1)) & 0x55555555;
    return v;
  };
  return (spread(x) | (spread(y) << 1)) >>> 0;
}

// The request key B as [hi, lo] (pack/tile_key.h's pack_request).
export function requestKey(p, l, x, y) {
  return [((p * 32) + (l & 31)) >>> 0, morton2(x, y)];
}

// The hash slot of key [hi, lo] in frame `frame` for a table of 2^bits slots.
export function hashSlot(hi, lo, frame, bits) {
  const salt = frame + FRAME_OFFSET;
  const [bh, bl] = mul64(hi, lo, Math.floor(salt / 2 ** 32) >>> 0, salt >>> 0);
  const [h] = mul64(A_HI, A_LO, bh, bl);
  return h >>> (32 - bits);
}

export class RequestProcessor {
  constructor(geometry, cache, pageTable, { tableBits = 16, perFrame = 16 } = {}) {
    if (!(tableBits >= 4 && tableBits <= 28)) throw new Error("tableBits must be in [4, 28]");
    this.geometry = geometry;
    this.cache = cache;
    this.pageTable = pageTable;
    this.bits = tableBits;
    this.perFrame = perFrame;
    const n = 1 << tableBits;
    this.slotIndex = new Uint32Array(n).fill(NONE);  // flat tile index held
    this.slotHi = new Uint32Array(n);
    this.slotLo = new Uint32Array(n);
    this.used = new Uint32Array(n);
    this.usedCount = 0;
    this.recent = new Uint32Array(256).fill(NONE);
    this.pending = [];          // commands left to issue, finest first
    this.inFlight = new Set();  // flat indices issued, not yet arrived
    this.last = { requests: 0, commands: 0, hits: 0, misses: 0, collisions: 0 };
  }

  // Inserts tile `index` into the frame's table (seed 000's collision rule).
  insert(index, frame) {
    const key = this.geometry.keyOf(index);
    if (!key) return;  // not a tile of the pack: ignored
    const [hi, lo] = requestKey(key[0], key[1], key[2], key[3]);
    const s = hashSlot(hi, lo, frame, this.bits);
    const held = this.slotIndex[s];
    if (held === NONE) {
      this.used[this.usedCount++] = s;
    } else {
      if (held === index) return;
      ++this.last.collisions;
      const lk = hi & 31, lh = this.slotHi[s] & 31;
      const wins = lk < lh || (lk === lh && (hi < this.slotHi[s] || (hi === this.slotHi[s] && lo < this.slotLo[s])));
      if (!wins) return;
    }
    this.slotIndex[s] = index;
    this.slotHi[s] = hi;
    this.slotLo[s] = lo;
  }

  // One frame's readbacks (Uint32Array of flat indices each) into requests and commands;
  // returns the distinct requests (flat indices).
  process(buffers, frame) {
    this.last = { requests: 0, commands: 0, hits: 0, misses: 0, collisions: 0 };
    const recent = this.recent;
    recent.fill(NONE);
    for (const keys of buffers) {
      let last = NONE;
      for (let i = 0, n = keys.length; i < n; ++i) {
        const v = keys[i];
        if (v === last) continue;
        last = v;
        if (v === NONE) continue;
        const r = Math.imul(v, 0x9e3779b1) >>> 24;
        if (recent[r] === v) continue;
        recent[r] = v;
        this.insert(v, frame);
      }
    }
    const requests = [];
    for (let k = 0; k < this.usedCount; ++k) {
      const s = this.used[k];
      requests.push(this.slotIndex[s]);
      this.slotIndex[s] = NONE;
    }
    this.usedCount = 0;
    this.resolve(requests);
    return requests;
  }

  // Responses and commands (resolve_requests + the cache's request()): a resident request is
  // a hit and becomes most recently used; a miss is a command. The commands replace the
  // previous set, finest level first (then by index: a fixed order).
  resolve(requests) {
    const commands = [];
    for (const index of requests) {
      if (this.cache.request(index)) ++this.last.hits;
      else { ++this.last.misses; commands.push(index); }
    }
    const level = (i) => this.geometry.keyOf(i)[1];
    commands.sort((a, b) => level(a) - level(b) || a - b);
    this.pending = commands;
    this.last.requests = requests.length;
    this.last.commands = commands.length;
  }

  // Up to perFrame (or `room`) commands that are neither resident nor in flight.
  issue(room = Infinity) {
    const out = [], keep = [];
    const cap = Math.min(this.perFrame, room);
    for (const index of this.pending) {
      if (this.cache.isResident(index) || this.inFlight.has(index)) continue;
      if (out.length < cap) { out.push(index); this.inFlight.add(index); } else keep.push(index);
    }
    this.pending = keep;
    return out;
  }

  arrived(index) { this.inFlight.delete(index); }
}
