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
// the repeat filter (the core's RepeatFilter: runs of the last key skipped 8 pixels at a
// time, and a cache of recent keys), so the per-pixel work is mostly one comparison.

import { NONE } from "./page_table.js";

const A_HI = 0x27bb2ee6, A_LO = 0x87b0b0fd;  // 2862933555777941757
export const FRAME_OFFSET = 2 ** 20 + 1;
// The repeat filter's cache of recent keys: 4096 entries, direct-mapped by a Fibonacci hash
// (the core's 256 a thread thrash when a frame's views see more tiles, as both eyes and the
// magnifier at level 0 do: ~500).
const RECENT = 4096, RECENT_SHIFT = 20;

// Low 64 bits of (ah 2^32 + al)(bh 2^32 + bl) into the scratch words H, L (no allocation:
// the frame loop calls it for every fresh key).
let H = 0, L = 0;
function mul64Into(ah, al, bh, bl) {
  const a0 = al & 0xffff, a1 = al >>> 16, b0 = bl & 0xffff, b1 = bl >>> 16;
  const p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  const mid = (p00 >>> 16) + (p01 & 0xffff) + (p10 & 0xffff);
  L = (((mid & 0xffff) << 16) | (p00 & 0xffff)) >>> 0;
  H = (p11 + Math.floor(p01 / 65536) + Math.floor(p10 / 65536) + Math.floor(mid / 65536) +
       Math.imul(ah, bl) + Math.imul(al, bh)) >>> 0;
}

// The same as [hi, lo] uint32.
export function mul64(ah, al, bh, bl) {
  mul64Into(ah, al, bh, bl);
  return [H, L];
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
  return saltedSlot(hi, lo, Math.floor(salt / 2 ** 32) >>> 0, salt >>> 0, bits);
}

// The same with the salt F as its words (sh, sl).
function saltedSlot(hi, lo, sh, sl, bits) {
  mul64Into(hi, lo, sh, sl);
  mul64Into(A_HI, A_LO, H, L);
  return H >>> (32 - bits);
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
    this.recent = new Int32Array(RECENT).fill(-1);
    this.key = new Int32Array(4);  // scratch tile key
    this.pending = [];          // commands left to issue, finest first
    this.inFlight = new Set();  // flat indices issued, not yet arrived
    this.last = { requests: 0, commands: 0, hits: 0, misses: 0, collisions: 0 };
  }

  // Inserts tile `index` into the frame's table (VT-mobile-VR's collision rule) under the salt's
  // words (sh, sl).
  insert(index, sh, sl) {
    const k = this.key;
    if (!this.geometry.keyInto(index, k)) return;  // not a tile of the pack: ignored
    const hi = (k[0] * 32 + k[1]) >>> 0, lo = morton2(k[2], k[3]);
    const s = saltedSlot(hi, lo, sh, sl, this.bits);
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
    const recent = this.recent, salt = frame + FRAME_OFFSET;
    const sh = Math.floor(salt / 2 ** 32) >>> 0, sl = salt >>> 0;
    recent.fill(-1);
    for (const keys of buffers) {
      // As int32 (NONE is -1): V8 keeps int32 loads in registers, uint32 ones above 2^31
      // become doubles. Blocks of 8 pixels equal to the last key are skipped with one test
      // (the core's RepeatFilter::scan); a feedback row repeats one tile for ~10 pixels, the
      // magnifier's 262k pixels hold a handful of tiles.
      const b = new Int32Array(keys.buffer, keys.byteOffset, keys.length), n = b.length;
      let last = -1, i = 0;
      while (i < n) {
        for (; i + 8 <= n; i += 8)
          if (((b[i] ^ last) | (b[i + 1] ^ last) | (b[i + 2] ^ last) | (b[i + 3] ^ last) | (b[i + 4] ^ last) |
               (b[i + 5] ^ last) | (b[i + 6] ^ last) | (b[i + 7] ^ last)) !== 0) break;
        for (const stop = Math.min(n, i + 8); i < stop; ++i) {
          const v = b[i];
          if (v === last) continue;
          last = v;
          if (v === -1) continue;
          const r = Math.imul(v, 0x9e3779b1) >>> RECENT_SHIFT;
          if (recent[r] === v) continue;
          recent[r] = v;
          this.insert(v >>> 0, sh, sl);
        }
      }
    }
    // Responses and commands (resolve_requests + the cache's request()): a resident request
    // is a hit and becomes most recently used; a miss is a command. The commands replace the
    // previous set, finest level first (then by index: a fixed order), sorted as level * 2^32
    // + index in a Float64Array (exact below 2^53).
    const requests = [], order = [];
    for (let k = 0; k < this.usedCount; ++k) {
      const s = this.used[k], index = this.slotIndex[s];
      requests.push(index);
      this.slotIndex[s] = NONE;
      if (this.cache.request(index)) ++this.last.hits;
      else { ++this.last.misses; order.push((this.slotHi[s] & 31) * 2 ** 32 + index); }
    }
    this.usedCount = 0;
    const sorted = Float64Array.from(order).sort();
    this.pending = Array.from(sorted, (x) => x % 2 ** 32);
    this.last.requests = requests.length;
    this.last.commands = sorted.length;
    return requests;
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
