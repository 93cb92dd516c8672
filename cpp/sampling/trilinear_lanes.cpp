// The 16-lane trilinear sampler (sampler.h's TrilinearLanes): the display pass's packets of
// 16 neighbouring pixels sampled in SIMD lanes, in named steps (the levels, each axis's
// origin and fractions, the common packet's stretches of texel rows, the general packet's
// taps and gathered corners). The general packet's steps are one text for every width
// (common/lanes.h: W lanes a step, the same floats at each); the common packet's stretches
// are AVX-512's byte permutes.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

#include "common/divider.h"
#include "common/lanes.h"
#include "sampling/sampler.h"
#include "sampling/texel_finder.h"

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace gigascroll {

// sample_trilinear_rgb8 for a packet of 16 samples in one or two resident tiles per level, in
// lanes: trilinear_taps' level rule and taps (in float from the packet's origin, see
// sample16), the texels at the same addresses (the 4-byte words of each footprint's corners),
// and blend_levels_rgb8's bilinear blends and blend of the levels. A sample that blends
// nothing (blend 0) takes its coarse taps at its fine level (as trilinear_taps leaves them)
// and adds 0 x (g - f) to f; so only the samples that blend two levels must share the
// coarse tile.
// GCC 12 warns that the _mm512_undefined_* sources inside its own AVX-512 intrinsics may be
// used uninitialized (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"  // the same, in _mm512_reduce_*_epi32
namespace {
// One level's taps for 16 lanes (trilinear_taps' second loop): weights, tile and in-tile
// byte offset.
struct LevelTaps {
    alignas(64) float fx[16], fy[16];
    alignas(64) std::int32_t level[16], cx[16], cy[16];
    alignas(64) std::int32_t row[16], offset[16];  // row: the footprint's first texel row in its tile
};
// trilinear_taps' level rule: each lane's fine level l0 (lo0 is max with 0 second, which
// maps NaN to 0 as the select does; below is min), which lanes blend two levels (lane k in
// bit k) and their weight.
struct LaneLevels {
    alignas(64) std::int32_t l0[16];
    alignas(64) float blend[16];
    unsigned blending = 0;
};
template <int W>
[[gnu::always_inline]] inline void lane_levels(const float* lod, float top, std::int32_t levels, LaneLevels& v) {
    using L = Lanes<W>;
    using F = typename L::F;
    using I = typename L::I;
    v.blending = 0;
    for (int k = 0; k < 16; k += W) {
        const F lod_c = min(max(F::load(lod + k), F(0.0f)), F(top));
        const I l0 = to_int(lod_c);
        const F frac = lod_c - L::to_float(l0);
        const auto blending = (frac > F(0.0f)) & (I(levels) > l0 + I(1));
        l0.store(v.l0 + k);
        L::select(blending, frac, F(0.0f)).store(v.blend + k);
        v.blending |= blending.bits() << k;
    }
}
#if defined(__AVX512F__)
// The byte masks of a stretch of span <= 128 bytes loaded as two 64-byte halves.
struct StretchMasks {
    __mmask64 first, second;
};
inline StretchMasks stretch_masks(int span) {
    return {span >= 64 ? ~__mmask64(0) : (__mmask64(1) << span) - 1,
            span > 64 ? (__mmask64(1) << (span - 64)) - 1 : 0};
}
// The two texel rows below a footprint's pair (its rows 2 and 3), the 128 bytes from its
// first texel on, fetched into the cache ahead of the next screen row's packets, which read
// them: at the fine level a screen row steps 1 to 2 texel rows down (a view of an upright
// painting), mostly onto rows no packet has read yet, and a tile's row is too short (6 cache
// lines) for the hardware's prefetcher to follow. The fetch of a row outside the slot is
// wasted, not an error (a prefetch does not fault).
[[gnu::always_inline]] inline void prefetch_rows_below(const std::uint8_t* first, std::int32_t row_bytes) {
    const std::uintptr_t below = reinterpret_cast<std::uintptr_t>(first) + 2 * std::uintptr_t(row_bytes);
    for (int row = 0; row < 2; ++row) {
        const std::uintptr_t q = below + std::uintptr_t(row) * std::uintptr_t(row_bytes);
        _mm_prefetch(reinterpret_cast<const char*>(q), _MM_HINT_T0);
        _mm_prefetch(reinterpret_cast<const char*>(q + 64), _MM_HINT_T0);
        _mm_prefetch(reinterpret_cast<const char*>(q + 127), _MM_HINT_T0);
    }
}
#endif
}  // namespace

struct TrilinearLanes::State {
    State(const VirtualTexture& vt, std::uint32_t painting)
        : finders{TexelFinder(vt, painting), TexelFinder(vt, painting), TexelFinder(vt, painting),
                  TexelFinder(vt, painting)},
          physical(vt.physical()), slot_bytes(vt.slot_bytes()),
          pyramid{vt.layout().paintings[painting].width(), vt.layout().paintings[painting].height(),
                  float(vt.layout().paintings[painting].levels() - 1)},
          levels(std::int32_t(vt.layout().paintings[painting].levels())),
          divide_p(vt.layout().payload()),
          tile{std::int32_t(vt.layout().payload()), std::int32_t(vt.layout().border),
               std::int32_t(vt.layout().tile_size), std::int32_t(finders[0].row_bytes())} {
        for (int j = 0; j < 6; ++j) std::fill_n(corner_bytes[j], 16, j);
        const PaintingGeometry& g = vt.layout().paintings[painting];
        for (std::uint32_t L = 0; L < g.levels(); ++L) {
            const double sx = std::ldexp(double(g.width()), -int(L)), sy = std::ldexp(double(g.height()), -int(L));
            axis_levels[0].push_back({sx, std::min(double(g.level_width(L)), sx) - 2.5});  // exact scales
            axis_levels[1].push_back({sy, std::min(double(g.level_height(L)), sy) - 2.5});
        }
    }

    // Per level (fine, coarse) and tile of a packet (first, other), the last page entry.
    TexelFinder finders[4];
    // Per axis (x, y) and level L, sample16's constants: the extent 2^-L (exact) and the
    // last position a packet's lanes may take at L less the origin, min(w_L, extent 2^-L) - 2.5
    // (see its axis).
    struct AxisLevel {
        double scale, limit;
    };
    std::vector<AxisLevel> axis_levels[2];
    // Byte j of a texel's corners (j = 3 x right + channel) in every lane: the stretch paths'
    // permute offsets, read as memory operands (as constants GCC made each anew at each use).
    alignas(64) std::int32_t corner_bytes[6][16];
    // Per finder, the last tile it looked up: its level, tile (cx, cy), its payload's first
    // texel (cx P, cy P) and its slot (nullptr: not resident). Finders 0 and 2 hold lane 0's
    // tile at the fine and coarse level, 1 and 3 the neighbour a packet across a tile's edge
    // took with it (or the tile lane 0 left). A packet whose lane 0 lies in either (most do: a
    // tile spans several packets) takes it without a division or a page-table entry.
    struct LastTile {
        std::int32_t level = -1, cx = 0, cy = 0, x0 = 0, y0 = 0;
        const std::uint8_t* base = nullptr;
    } last_tile[4];
    const std::uint8_t* physical;
    std::size_t slot_bytes;
    PyramidExtent pyramid;
    std::int32_t levels;
    Divider divide_p;
    TileExtent tile;

    // The slot of level l's resident tile (cx, cy) through finder c, nullptr for a fallback.
    const std::uint8_t* base(int c, std::uint32_t l, std::uint32_t cx, std::uint32_t cy) {
        const PageEntry e = finders[c].entry(l, cx, cy);
        return e.level() == l ? physical + std::size_t(e.slot()) * slot_bytes : nullptr;
    }
    // sample16's steps (see there).
    static constexpr std::uint32_t kMaxSide = 1u << 22;
    struct Axis;
    struct Position;
    struct LevelTiles;
    static void level_origin(const Axis& a, int k, std::int32_t& origin, float& frac);
    template <int W>
    static bool axis(double c0, const AxisLevel& level, const float* d, Axis& a);
    template <int W>
    void taps(const Position& pp, const std::int32_t* l, LevelTaps& lt) const;
    template <int W>
    bool tiles(const LevelTaps& lt, int c, unsigned mask, LevelTiles& out);
    template <int W>
    void corners(const LevelTaps& lt, const std::uint8_t* base, unsigned mask, int k0, typename Lanes<W>::I (&q)[4]) const;
    template <int W>
    void bilinear(const LevelTaps& lt, const LevelTiles& tl, int k0, typename Lanes<W>::F& R, typename Lanes<W>::F& G,
                  typename Lanes<W>::F& B) const;
    template <int W>
    bool sample(const LevelTaps& fine_taps, const LevelTaps& coarse_taps, const LaneLevels& lv, float* r, float* g,
                float* b);
#if defined(__AVX512F__)
    // The stretches of a level's pair of texel rows (see sample16) for a packet across a
    // tile's edge: lane 0's tile last_tile[finder] (tile x0 in lane coordinates x0_lanes,
    // in_tile its lanes) and its neighbour, into rows[r] = {bytes 0-63, 64-127}. False when
    // the other lanes are not all in the payload of the neighbour on one side or it is not
    // resident.
    bool across_edge(int level, int finder, __m512i nx_lanes, std::int32_t x0_lanes, __mmask16 in_tile,
                     std::int32_t lo, std::int32_t span, std::size_t row_start, __m512i (&rows)[2][2]);
#endif
#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
    bool stretch_corners(const LevelTaps& lt, const std::uint8_t* base, unsigned mask, __m512i (&q)[4]) const;
    struct LevelPosition;
    struct Stretch;
    LevelPosition level_position(const Position& pp, int k) const;
    Stretch stretch_in(const LevelPosition& p, const LastTile& last) const;
    void blend_rows(const __m512i (&rows)[2][2], const Stretch& s, const LevelPosition& p, __m512& R, __m512& G,
                    __m512& B) const;
    bool holds(const LastTile& c, std::int32_t l, std::int32_t x, std::int32_t y) const;
    bool one_tile(const Position& pp, int k, int finder, __m512& R, __m512& G, __m512& B);
    bool two_tiles(const Position& pp, int k, int finder, __m512& R, __m512& G, __m512& B);
    bool sample_stretches(const Position& pp, const LaneLevels& lv, float* r, float* g, float* b);
#endif
};

TrilinearLanes::TrilinearLanes(const VirtualTexture& vt, std::uint32_t painting) {
    // Disabled for a painting the texture does not hold: sample() says so.
    if (vt.format() == TexelFormat::Rgb8 && painting < vt.layout().paintings.size())
        state_ = std::make_unique<State>(vt, painting);
}
void TrilinearLanes::forget_tiles() {
    if (!state_) return;
    for (TexelFinder& f : state_->finders) f.forget();
    for (State::LastTile& t : state_->last_tile) t.level = -1;
}
TrilinearLanes::~TrilinearLanes() = default;
TrilinearLanes::TrilinearLanes(TrilinearLanes&&) noexcept = default;

// The tiles of the lanes in mask at their level: the first lane's and, for a packet across a
// tile edge, one other, each resident (its slot) with the lanes it holds.
struct TrilinearLanes::State::LevelTiles {
    const std::uint8_t* base[2];
    unsigned lanes[2];
    int count;
};
// False for a third tile or a tile that is not resident (a fallback).
template <int W>
[[gnu::always_inline]] inline bool TrilinearLanes::State::tiles(const LevelTaps& lt, int c, unsigned mask, LevelTiles& out) {
    using I = typename Lanes<W>::I;
    out.count = 0;
    for (int k = 0; k < 2 && mask; ++k) {
        const int first = std::countr_zero(mask);  // lane 0 nearly always
        const std::int32_t l = lt.level[first], cx = lt.cx[first], cy = lt.cy[first];
        unsigned same = 0;
        for (int k0 = 0; k0 < 16; k0 += W)
            same |= ((I::load(lt.level + k0) == I(l)) & (I::load(lt.cx + k0) == I(cx)) & (I::load(lt.cy + k0) == I(cy)))
                        .bits() << k0;
        same &= mask;
        out.base[k] = base(2 * c + k, std::uint32_t(l), std::uint32_t(cx), std::uint32_t(cy));
        if (!out.base[k]) return false;
        out.lanes[k] = same, out.count = k + 1;
        mask &= ~same;
    }
    return mask == 0;
}

// The 4-byte words at lanes k0 .. k0 + W - 1's footprint corners (offset, + 3, + row,
// + row + 3: the texel and its right neighbour in two rows), q[0..3]: gathered, or at 16
// lanes picked out of the rows' stretches (stretch_corners) where they fit.
template <int W>
[[gnu::always_inline]] inline void TrilinearLanes::State::corners(const LevelTaps& lt, const std::uint8_t* base, unsigned mask, int k0,
                                    typename Lanes<W>::I (&q)[4]) const {
    using I = typename Lanes<W>::I;
#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
    if constexpr (W == 16) {
        __m512i words[4];
        if (stretch_corners(lt, base, mask, words)) {
            for (int k = 0; k < 4; ++k) q[k] = I(words[k]);
            return;
        }
    }
#endif
    (void)mask;
    const std::int32_t row = tile.row_bytes;
    const std::int32_t delta[4] = {0, 3, row, row + 3};
    const I offset = I::load(lt.offset + k0);
    for (int k = 0; k < 4; ++k) q[k] = gather_bytes(base, offset + I(delta[k]));
}

#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
// When the lanes in mask share the footprint's texel rows and their corners span at most 128
// bytes (nearly always: a packet of neighbouring pixels reads one stretch of two rows), the
// two stretches loaded (masked to the bytes the gathers would read) and the words picked out
// with byte permutes; false otherwise. The lanes outside mask get some word of the stretch.
[[gnu::always_inline]] inline bool TrilinearLanes::State::stretch_corners(const LevelTaps& lt, const std::uint8_t* base,
                                                                         unsigned mask16, __m512i (&q)[4]) const {
    const __mmask16 mask = __mmask16(mask16);
    const __m512i offset = _mm512_load_si512(lt.offset), row_of = _mm512_load_si512(lt.row);
    const std::int32_t row = tile.row_bytes;
    const int lo = _mm512_mask_reduce_min_epi32(mask, offset);
    const int hi = _mm512_mask_reduce_max_epi32(mask, offset);
    const int span = hi - lo + 7;  // bytes lo .. hi + 6
    const int first_row = lt.row[std::countr_zero(mask16)];
    if (span > 128 || _mm512_mask_cmpneq_epi32_mask(mask, row_of, _mm512_set1_epi32(first_row))) return false;
    const __m512i rel = _mm512_maskz_sub_epi32(mask, offset, _mm512_set1_epi32(lo));
    // Each lane's byte index rel + 0..3 (rel < 128: one byte).
    const __m512i spread = _mm512_broadcast_i32x4(_mm_setr_epi8(0, 0, 0, 0, 4, 4, 4, 4, 8, 8, 8, 8, 12, 12, 12, 12));
    const __m512i idx = _mm512_add_epi8(_mm512_shuffle_epi8(rel, spread), _mm512_set1_epi32(0x03020100));
    const __m512i idx3 = _mm512_add_epi8(idx, _mm512_set1_epi8(3));
    const auto [m0, m1] = stretch_masks(span);
    for (int r = 0; r < 2; ++r) {
        const std::uint8_t* p = base + lo + r * row;
        const __m512i a = _mm512_maskz_loadu_epi8(m0, p), b = _mm512_maskz_loadu_epi8(m1, p + 64);
        q[2 * r] = _mm512_permutex2var_epi8(a, idx, b);
        q[2 * r + 1] = _mm512_permutex2var_epi8(a, idx3, b);
    }
    return true;
}
#endif

// One level's bilinear blend of lanes k0 .. k0 + W - 1: channels R, G, B.
template <int W>
[[gnu::always_inline]] inline void TrilinearLanes::State::bilinear(const LevelTaps& lt, const LevelTiles& tl, int k0,
                                                                  typename Lanes<W>::F& R, typename Lanes<W>::F& G,
                                                                  typename Lanes<W>::F& B) const {
    using L = Lanes<W>;
    using F = typename L::F;
    using I = typename L::I;
    const F one(1.0f), fx = F::load(lt.fx + k0), fy = F::load(lt.fy + k0);
    const F gx = one - fx, gy = one - fy;
    const F w[4] = {gx * gy, fx * gy, gx * fy, fx * fy};
    I words[4];
    corners<W>(lt, tl.base[0], tl.lanes[0], k0, words);
    if (tl.count == 2) {  // the lanes in the other tile
        I other[4];
        corners<W>(lt, tl.base[1], tl.lanes[1], k0, other);
        const auto in_other = mask_of<W>(tl.lanes[1] >> k0);
        for (int q = 0; q < 4; ++q) words[q] = L::select(in_other, other[q], words[q]);
    }
    const I byte(0xff);
    for (int q = 0; q < 4; ++q) {
        const F tr = L::to_float(words[q] & byte), tg = L::to_float(srl(words[q], 8) & byte);
        const F tb = L::to_float(srl(words[q], 16) & byte);
        if (q == 0) {
            R = w[0] * tr, G = w[0] * tg, B = w[0] * tb;
        } else {
            R = fma(w[q], tr, R), G = fma(w[q], tg, G), B = fma(w[q], tb, B);
        }
    }
}

// The samples from their fine and (for the lanes in levels.blending) coarse taps: each
// level's tiles, texels and bilinear blend, then the blend of the two levels.
template <int W>
[[gnu::always_inline]] inline bool TrilinearLanes::State::sample(const LevelTaps& fine_taps, const LevelTaps& coarse_taps, const LaneLevels& lv,
                                   float* r, float* g, float* b) {
    using F = typename Lanes<W>::F;
    LevelTiles fine, coarse;
    if (!tiles<W>(fine_taps, 0, 0xFFFF, fine)) return false;
    if (lv.blending && !tiles<W>(coarse_taps, 1, lv.blending, coarse)) return false;
    for (int k = 0; k < 16; k += W) {
        F R, G, B;
        bilinear<W>(fine_taps, fine, k, R, G, B);
        if (lv.blending) {  // f + blend (g - f); the lanes that blend nothing read their fine level again
            F R1, G1, B1;
            bilinear<W>(coarse_taps, coarse, k, R1, G1, B1);
            const F blend = F::load(lv.blend + k);
            R = fma(blend, R1 - R, R), G = fma(blend, G1 - G, G), B = fma(blend, B1 - B, B);
        }
        R.store(r + k), G.store(g + k), B.store(b + k);
    }
    return true;
}

#if defined(__AVX512F__)
// The neighbour is lane 0's tile's cx -+ 1 (a packet's lanes lie in a row of tiles), its
// bytes addressed from lane 0's tile's lo: the neighbour's texel x is lane 0's tile's -+ P.
// It exists: sample16's range check keeps every lane two texels inside the painting.
[[gnu::always_inline]] inline bool TrilinearLanes::State::across_edge(int level, int finder, __m512i nx_lanes,
                                                                     std::int32_t x0_lanes, __mmask16 in_tile,
                                                                     std::int32_t lo, std::int32_t span,
                                                                     std::size_t row_start, __m512i (&rows)[2][2]) {
    const TileExtent t = tile;
    const LastTile& own = last_tile[finder];
    LastTile& other = last_tile[finder + 1];
    const __mmask16 others = __mmask16(~in_tile);
    // The other lanes in the right neighbour's payload, or all in the left one's.
    const bool right = _mm512_mask_cmplt_epi32_mask(others, nx_lanes, _mm512_set1_epi32(x0_lanes + t.payload)) == 0;
    const std::int32_t side = right ? 1 : -1;
    if (_mm512_mask_cmpge_epu32_mask(others, _mm512_sub_epi32(nx_lanes, _mm512_set1_epi32(x0_lanes + side * t.payload)),
                                     _mm512_set1_epi32(t.payload)))
        return false;
    if (other.level != level || other.x0 != own.x0 + side * t.payload || other.y0 != own.y0) {
        const std::int32_t cx = own.cx + side;
        other = {level, cx, own.cy, own.x0 + side * t.payload, own.y0,
                 base(finder + 1, std::uint32_t(level), std::uint32_t(cx), std::uint32_t(own.cy))};
    }
    if (!other.base) return false;
    // The row's bytes from lo on: the left tile's before byte `split` (the right tile's first
    // payload texel), the right tile's from there (a border holds its neighbour's texels, so
    // both tiles hold the same bytes around it). A tile's bytes before its slot, if any, are
    // masked off: masked loads do not touch them.
    const std::int32_t split = 3 * (t.border + (right ? t.payload : 0) - lo);  // in (0, span)
    const StretchMasks all = stretch_masks(span), left = stretch_masks(split);
    auto at = [](const std::uint8_t* slot, std::ptrdiff_t offset) {  // no out-of-object pointer formed
        return reinterpret_cast<const std::uint8_t*>(reinterpret_cast<std::uintptr_t>(slot) + std::uintptr_t(offset));
    };
    const std::ptrdiff_t first = std::ptrdiff_t(row_start) + 3 * std::ptrdiff_t(lo), shift = 3 * std::ptrdiff_t(t.payload);
    const std::ptrdiff_t left_at = first + (right ? 0 : shift), right_at = first - (right ? shift : 0);
    const std::uint8_t* left_slot = right ? own.base : other.base;
    const std::uint8_t* right_slot = right ? other.base : own.base;
    for (int row = 0; row < 2; ++row) {
        const std::ptrdiff_t l = left_at + row * t.row_bytes, r = right_at + row * t.row_bytes;
        rows[row][0] = _mm512_mask_loadu_epi8(_mm512_maskz_loadu_epi8(all.first & left.first, at(left_slot, l)),
                                              all.first & ~left.first, at(right_slot, r));
        rows[row][1] = _mm512_mask_loadu_epi8(_mm512_maskz_loadu_epi8(all.second & left.second, at(left_slot, l + 64)),
                                              all.second & ~left.second, at(right_slot, r + 64));
    }
    return true;
}

#endif

// sample16's packet position at its finest level L on one axis: lane 0's continuous texel
// position less 1/2 (trilinear_taps' tx before its clamp), X = c0 extent 2^-L - 1/2, as an
// integer origin and a fraction; each lane's position relative to the origin is frac +
// d extent 2^-L in float. Level L + k's position is (X + 1/2) 2^-k - 1/2 = origin_k +
// (rel 2^-k + frac_k), with origin_k and frac_k the same split of (origin + 1/2) 2^-k - 1/2
// (level_origin, exact).
struct TrilinearLanes::State::Axis {
    alignas(64) float rel[16];  // per lane, at level L
    std::int32_t origin;        // at level L
};
struct TrilinearLanes::State::Position {
    Axis ax, ay;
    std::int32_t L;  // the packet's finest level
};

// Level L + k's origin and fraction: (o + 1/2) 2^-k - 1/2 = (2o + 1 - 2^k) / 2^(k+1), its
// floor by an arithmetic shift, its fraction in eighths (made where a level needs them).
[[gnu::always_inline]] inline void TrilinearLanes::State::level_origin(const Axis& a, int k, std::int32_t& origin,
                                                                      float& frac) {
    const std::int32_t num = 2 * a.origin + 1 - (1 << k);
    origin = num >> (k + 1);
    frac = float(num & ((2 << k) - 1)) / float(2 << k);
}

// One axis of the packet at level L from lane 0's coordinate c0 and the lanes' offsets d;
// false where a lane comes within two texels of the painting's edge (or NaN, far outside).
template <int W>
[[gnu::always_inline]] inline bool TrilinearLanes::State::axis(double c0, const AxisLevel& level, const float* d,
                                                              Axis& a) {
    using F = typename Lanes<W>::F;
    // c0 extent 2^-L as (c0 extent) 2^-L: the scaling by a power of two is exact.
    const double X = c0 * level.scale - 0.5;
    const double o = std::floor(X);
    if (!(std::abs(o) < double(kMaxSide))) return false;  // NaN or far outside
    // Two texels inside the painting at level L, so that at levels L, L + 1 and L + 2 no
    // lane reaches trilinear_taps' clamps (to [0, w_l - 1], and of uv to [0, 1]):
    // X_{L+k} = (X + 1/2) 2^-k - 1/2 >= 5/8 - 1/2 > 0 and <= w_{L+k} - 1.
    const F lo(float(2.0 - o)), hi(float(level.limit - o));
    for (int k = 0; k < 16; k += W) {
        const F rel = fma(F::load(d + k), F(float(level.scale)), F(float(X - o)));
        if (any<W>((rel < lo) | (rel > hi))) return false;
        rel.store(a.rel + k);
    }
    a.origin = std::int32_t(o);
    return true;
}

#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
// Level L + k's origins, each lane's texel from them (the floor of its position) and its
// weights.
struct TrilinearLanes::State::LevelPosition {
    std::int32_t ox, oy;
    __m512 fx, fy;
    __m512i ix, iy, nx, ny;
};
[[gnu::always_inline]] inline TrilinearLanes::State::LevelPosition TrilinearLanes::State::level_position(
    const Position& pp, int k) const {
    LevelPosition p;
    p.ox = pp.ax.origin, p.oy = pp.ay.origin;
    __m512 x = _mm512_load_ps(pp.ax.rel), y = _mm512_load_ps(pp.ay.rel);
    if (k) {
        float fx0, fy0;
        level_origin(pp.ax, k, p.ox, fx0), level_origin(pp.ay, k, p.oy, fy0);
        const __m512 half = _mm512_set1_ps(0.5f);
        x = _mm512_fmadd_ps(x, half, _mm512_set1_ps(fx0)), y = _mm512_fmadd_ps(y, half, _mm512_set1_ps(fy0));
    }
    const __m512 x_fl = _mm512_roundscale_ps(x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
    const __m512 y_fl = _mm512_roundscale_ps(y, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
    p.fx = _mm512_sub_ps(x, x_fl), p.fy = _mm512_sub_ps(y, y_fl);
    p.ix = _mm512_cvttps_epi32(x_fl), p.iy = _mm512_cvttps_epi32(y_fl);
    // Every lane's nearest texel (trilinear_taps' n_up), less the origin.
    const __m512 half = _mm512_set1_ps(0.5f);
    const __m512i one_i = _mm512_set1_epi32(1);
    p.nx = _mm512_mask_add_epi32(p.ix, _mm512_cmp_ps_mask(p.fx, half, _CMP_GE_OQ), p.ix, one_i);
    p.ny = _mm512_mask_add_epi32(p.iy, _mm512_cmp_ps_mask(p.fy, half, _CMP_GE_OQ), p.iy, one_i);
    return p;
}

// At a level's position p in lane 0's tile: each lane's footprint's first texel in the tile
// (border included), the stretch of bytes from lo on that the footprints' corners span on
// their rows, and whether it fits one byte permute: every footprint on the same pair of
// texel rows, within 128 bytes.
struct TrilinearLanes::State::Stretch {
    std::int32_t first_row, lo, span;
    __m512i rel;  // each lane's first texel less lo
    bool fits;
};
[[gnu::always_inline]] inline TrilinearLanes::State::Stretch TrilinearLanes::State::stretch_in(
    const LevelPosition& p, const LastTile& last) const {
    const TileExtent t = tile;
    Stretch s;
    const __m512i jx = _mm512_sub_epi32(p.ix, _mm512_set1_epi32(last.x0 - t.border - p.ox));
    const __m512i jy = _mm512_sub_epi32(p.iy, _mm512_set1_epi32(last.y0 - t.border - p.oy));
    s.first_row = _mm_cvtsi128_si32(_mm512_castsi512_si128(jy));
    const std::int32_t jx_a = _mm_cvtsi128_si32(_mm512_castsi512_si128(jx));
    const std::int32_t jx_b = _mm_extract_epi32(_mm512_extracti32x4_epi32(jx, 3), 3);
    s.lo = std::min(jx_a, jx_b);
    const std::int32_t hi = std::max(jx_a, jx_b);
    s.rel = _mm512_sub_epi32(jx, _mm512_set1_epi32(s.lo));
    s.span = 3 * (hi - s.lo) + 6;  // bytes of the corners' channels
    s.fits = !(_mm512_cmpneq_epi32_mask(jy, _mm512_set1_epi32(s.first_row)) |
               _mm512_cmpgt_epu32_mask(s.rel, _mm512_set1_epi32(hi - s.lo))) &&
             s.span <= 128;
    return s;
}

// A level's bilinear blends of 16 lanes from each row's stretch (its two 64-byte halves):
// every channel of every corner picked into its lane by one byte permute.
[[gnu::always_inline]] inline void TrilinearLanes::State::blend_rows(const __m512i (&rows)[2][2], const Stretch& s,
                                                                    const LevelPosition& p, __m512& R, __m512& G,
                                                                    __m512& B) const {
    // Each lane's first byte in its dword, the others zeroed by the permutes' mask.
    const __m512i byte0 = _mm512_add_epi32(s.rel, _mm512_add_epi32(s.rel, s.rel));
    constexpr __mmask64 kLowBytes = 0x1111111111111111ull;
    const __m512 one = _mm512_set1_ps(1.0f);
    const __m512 gx = _mm512_sub_ps(one, p.fx), gy = _mm512_sub_ps(one, p.fy);
    const __m512 w[2][2] = {{_mm512_mul_ps(gx, gy), _mm512_mul_ps(p.fx, gy)},
                            {_mm512_mul_ps(gx, p.fy), _mm512_mul_ps(p.fx, p.fy)}};
    __m512 sum[3];
    for (int row = 0; row < 2; ++row)
        for (int right = 0; right < 2; ++right)
            for (int c = 0; c < 3; ++c) {
                const int corner = 3 * right + c;
                const __m512i idx = corner ? _mm512_add_epi32(byte0, _mm512_load_si512(corner_bytes[corner])) : byte0;
                const __m512 texel = _mm512_cvtepi32_ps(_mm512_maskz_permutex2var_epi8(kLowBytes, rows[row][0], idx, rows[row][1]));
                sum[c] = row == 0 && right == 0 ? _mm512_mul_ps(w[0][0], texel)
                                                : _mm512_fmadd_ps(w[row][right], texel, sum[c]);
            }
    R = sum[0], G = sum[1], B = sum[2];
}

// Whether the last tile c at level l holds texel (x, y) (its cx = floor(x / P) exactly when
// x - cx P lies in [0, P)).
[[gnu::always_inline]] inline bool TrilinearLanes::State::holds(const LastTile& c, std::int32_t l, std::int32_t x, std::int32_t y) const {
    return c.level == l && std::uint32_t(x - c.x0) < std::uint32_t(tile.payload) &&
           std::uint32_t(y - c.y0) < std::uint32_t(tile.payload);
}

// Level L + k when its lanes' nearest texels (trilinear_taps' tile for each lane) all lie in
// lane 0's tile, through finder `finder`.
[[gnu::always_inline]] inline bool TrilinearLanes::State::one_tile(const Position& pp, int k, int finder, __m512& R,
                                                                  __m512& G, __m512& B) {
    const TileExtent t = tile;
    const std::int32_t level = pp.L + k;
    const LevelPosition p = level_position(pp, k);
    // Lane 0's tile by its nearest texel, as trilinear_taps: the last one's, or the
    // neighbour last taken with it, when either holds that texel.
    const std::int32_t nx = p.ox + _mm_cvtsi128_si32(_mm512_castsi512_si128(p.nx));
    const std::int32_t ny = p.oy + _mm_cvtsi128_si32(_mm512_castsi512_si128(p.ny));
    LastTile& own = last_tile[finder];
    if (!holds(own, level, nx, ny)) {
        LastTile& other = last_tile[finder + 1];
        if (holds(other, level, nx, ny)) {
            std::swap(own, other);
        } else {
            const std::uint32_t cx = divide_p(std::uint32_t(nx)), cy = divide_p(std::uint32_t(ny));
            own = {level, std::int32_t(cx), std::int32_t(cy), std::int32_t(cx) * t.payload, std::int32_t(cy) * t.payload,
                   base(finder, std::uint32_t(level), cx, cy)};
        }
    }
    const Stretch s = stretch_in(p, own);
    // Every lane's nearest texel in the tile's payload (its tile is lane 0's: a lane of
    // another tile would read this one's border where trilinear_taps might fall back).
    const __m512i payload = _mm512_set1_epi32(t.payload);
    if ((_mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.nx, _mm512_set1_epi32(own.x0 - p.ox)), payload) &
         _mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.ny, _mm512_set1_epi32(own.y0 - p.oy)), payload)) != 0xFFFF ||
        !s.fits || !own.base)
        return false;
    const std::uint8_t* first = own.base + std::size_t(s.first_row) * std::size_t(t.row_bytes) + std::size_t(s.lo) * 3;
    const auto [m0, m1] = stretch_masks(s.span);
    prefetch_rows_below(first, t.row_bytes);
    __m512i rows[2][2];
    for (int row = 0; row < 2; ++row) {
        const std::uint8_t* q = first + row * t.row_bytes;
        rows[row][0] = _mm512_maskz_loadu_epi8(m0, q), rows[row][1] = _mm512_maskz_loadu_epi8(m1, q + 64);
    }
    blend_rows(rows, s, p, R, G, B);
    return true;
}

// Level L + k when its lanes lie in lane 0's tile and its neighbour on the left or right (a
// packet across a tile's edge; one_tile declined it, leaving lane 0's tile in
// last_tile[finder]): one_tile's checks for the lanes' two tiles, each row's stretch as the
// level's bytes from both (across_edge). The position and stretch are one_tile's, made again
// rather than handed over: GCC shares them, and one function for both paths cost the common
// packets more (bench/RESULTS.md at 177a369).
[[gnu::always_inline]] inline bool TrilinearLanes::State::two_tiles(const Position& pp, int k, int finder, __m512& R,
                                                                   __m512& G, __m512& B) {
    const TileExtent t = tile;
    const LevelPosition p = level_position(pp, k);
    const LastTile& own = last_tile[finder];
    const Stretch s = stretch_in(p, own);
    const __m512i payload = _mm512_set1_epi32(t.payload);
    const __mmask16 in_tile = _mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.nx, _mm512_set1_epi32(own.x0 - p.ox)), payload);
    __m512i rows[2][2];
    if (in_tile == 0xFFFF || !own.base || !s.fits ||
        _mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.ny, _mm512_set1_epi32(own.y0 - p.oy)), payload) != 0xFFFF ||
        !across_edge(pp.L + k, finder, p.nx, own.x0 - p.ox, in_tile, s.lo, s.span,
                     std::size_t(s.first_row) * std::size_t(t.row_bytes), rows))
        return false;
    blend_rows(rows, s, p, R, G, B);
    return true;
}

// The common packet in fewer steps: every lane's fine level L, and at each level every lane's
// nearest texel in one tile (trilinear_taps' tile for every lane) or two neighbouring ones,
// and its footprint on one pair of texel rows. Per level, each row's stretch is loaded once
// and every channel of every corner picked into its own lane by one byte permute. The same
// taps, texels, products and sums as sample's.
[[gnu::always_inline]] inline bool TrilinearLanes::State::sample_stretches(const Position& pp, const LaneLevels& lv,
                                                                          float* r, float* g, float* b) {
    __m512 R, G, B, R1, G1, B1;
    if (!(one_tile(pp, 0, 0, R, G, B) || two_tiles(pp, 0, 0, R, G, B))) return false;
    if (lv.blending && !(one_tile(pp, 1, 2, R1, G1, B1) || two_tiles(pp, 1, 2, R1, G1, B1))) return false;
    if (lv.blending) {
        const __m512 blend = _mm512_load_ps(lv.blend);
        R = _mm512_fmadd_ps(blend, _mm512_sub_ps(R1, R), R);
        G = _mm512_fmadd_ps(blend, _mm512_sub_ps(G1, G), G);
        B = _mm512_fmadd_ps(blend, _mm512_sub_ps(B1, B), B);
    }
    _mm512_storeu_ps(r, R), _mm512_storeu_ps(g, G), _mm512_storeu_ps(b, B);
    return true;
}
#endif


// One level's taps for the general packet from the lanes' levels l (L or L + 1 or L + 2).
template <int W>
[[gnu::always_inline]] inline void TrilinearLanes::State::taps(const Position& pp, const std::int32_t* ls,
                                                              LevelTaps& lt) const {
    using L = Lanes<W>;
    using F = typename L::F;
    using I = typename L::I;
    const TileExtent t = tile;
    const F inv_p(1.0f / float(t.payload));
    for (int k0 = 0; k0 < 16; k0 += W) {
        const I l = I::load(ls + k0);
        const I k = l - I(pp.L);
        const auto k1 = k == I(1), k2 = k == I(2);
        auto one_axis = [&](const Axis& a, float* f_out, std::int32_t* cell_out) {
            F x = F::load(a.rel + k0);
            I origin(a.origin);
            if (any<W>(k1 | k2)) {  // not every lane at level L (rare)
                std::int32_t o1, o2;
                float f1, f2;
                level_origin(a, 1, o1, f1), level_origin(a, 2, o2, f2);
                const F frac = L::select(k2, F(f2), L::select(k1, F(f1), F(0.0f)));
                origin = L::select(k2, I(o2), L::select(k1, I(o1), origin));
                // x 2^-k (exact) plus the level's fraction.
                x = x * L::select(k2, F(0.25f), L::select(k1, F(0.5f), F(1.0f))) + frac;
            }
            const F fl = floor(x);
            const F f = x - fl;
            const I i = origin + to_int(fl);
            const I n_up = L::select(f >= F(0.5f), i + I(1), i);
            // floor(n_up / P) as Divider::by_double in float: (n + 1/2) fl(1/P) is within
            // 2^-23 (n + 1/2) / P of (n + 1/2) / P, below 1 / (2P) for n < 2^22.
            const I cell = to_int((L::to_float(n_up) + F(0.5f)) * inv_p);
            const I j = i - cell * I(t.payload) + I(t.border);
            f.store(f_out + k0), cell.store(cell_out + k0);
            return min(max(j, I(0)), I(t.tile - 2));  // the footprint's first texel in its tile
        };
        const I jx = one_axis(pp.ax, lt.fx, lt.cx), jy = one_axis(pp.ay, lt.fy, lt.cy);
        l.store(lt.level + k0), jy.store(lt.row + k0);
        (jy * I(t.row_bytes) + jx * I(3)).store(lt.offset + k0);
    }
}

// The packet's levels (its finest L and at most L + 1 at the fine level, so L + 2 at the
// coarse one), its position on each axis, then the common packet's stretches or the general
// packet's taps and gathered corners.
template <int W>
bool TrilinearLanes::sample_lanes(const PacketUv& packet, float* r, float* g, float* b, bool stretches) {
    using L = Lanes<W>;
    using I = typename L::I;
    if (!state_) return false;
    State& st = *state_;
    // Below 2^22 texels a side the float tile division is exact (see taps) and every texel
    // index and level extent is a float.
    if (st.pyramid.width >= State::kMaxSide || st.pyramid.height >= State::kMaxSide) return false;
    LaneLevels lv;
    lane_levels<W>(packet.lod, st.pyramid.top, st.levels, lv);
    // Nearly always every lane's level is lane 0's.
    State::Position pp;
    pp.L = lv.l0[0];
    bool levels_differ = false;
    for (int k = 0; k < 16; k += W) levels_differ = levels_differ || any<W>(I::load(lv.l0 + k) != I(pp.L));
    if (levels_differ) {
        const auto [lowest, highest] = std::minmax_element(lv.l0, lv.l0 + 16);
        pp.L = *lowest;
        if (*highest > pp.L + 1) return false;
    }
    if (!State::axis<W>(packet.u0, st.axis_levels[0][std::size_t(pp.L)], packet.du, pp.ax) ||
        !State::axis<W>(packet.v0, st.axis_levels[1][std::size_t(pp.L)], packet.dv, pp.ay))
        return false;
    // NaN positions fail neither comparison in axis: refuse them here.
    for (int k = 0; k < 16; k += W) {
        const typename L::F x = L::F::load(pp.ax.rel + k), y = L::F::load(pp.ay.rel + k);
        if (any<W>(!(x <= x) | !(y <= y))) return false;
    }
#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
    if constexpr (W == 16)
        if (stretches && !levels_differ && st.sample_stretches(pp, lv, r, g, b)) return true;
#endif
    (void)stretches;
    LevelTaps fine_taps;
    st.taps<W>(pp, lv.l0, fine_taps);
    if (!lv.blending) return st.sample<W>(fine_taps, fine_taps, lv, r, g, b);
    alignas(64) std::int32_t l1[16];
    for (int k = 0; k < 16; k += W)
        L::select(mask_of<W>(lv.blending >> k), I::load(lv.l0 + k) + I(1), I::load(lv.l0 + k)).store(l1 + k);
    LevelTaps coarse_taps;
    st.taps<W>(pp, l1, coarse_taps);
    return st.sample<W>(fine_taps, coarse_taps, lv, r, g, b);
}
template bool TrilinearLanes::sample_lanes<1>(const PacketUv&, float*, float*, float*, bool);
#if defined(__AVX2__)
template bool TrilinearLanes::sample_lanes<8>(const PacketUv&, float*, float*, float*, bool);
#endif
#if defined(__AVX512F__)
template bool TrilinearLanes::sample_lanes<16>(const PacketUv&, float*, float*, float*, bool);
#endif

bool TrilinearLanes::enabled() const { return state_ != nullptr && kWidest == 16; }

bool TrilinearLanes::sample16(const PacketUv& packet, float* r, float* g, float* b) {
#if defined(__AVX512F__)
    return sample_lanes<16>(packet, r, g, b, true);
#else
    (void)packet, (void)r, (void)g, (void)b;
    return false;  // no lanes to sample in: always declined
#endif
}
#pragma GCC diagnostic pop

}  // namespace gigascroll
