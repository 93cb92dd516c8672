#include "sampling/sampler.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <mutex>
#include <shared_mutex>

#include "common/divider.h"
#include "common/error.h"
#include "common/parallel.h"
#include "pack/bc1.h"
#include "sampling/bilinear.h"
#include "sampling/texel_finder.h"

#if defined(__AVX2__)
#include <immintrin.h>
#endif

namespace gigascroll {

Filter parse_filter(const std::string& f) {
    if (f == "bilinear") return Filter::Bilinear;
    if (f == "trilinear") return Filter::Trilinear;
    throw InvalidArgument("filter must be 'bilinear' or 'trilinear', got '" + f + "'");
}

namespace {
void sample_range(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin, std::size_t end);
template <TexelFormat F>
void sample_bilinear(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin, std::size_t end);
template <TexelFormat F>
void sample_trilinear(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin, std::size_t end);
void sample_trilinear_rgb8(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin,
                           std::size_t end);
void sample_trilinear_serial(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin,
                             std::size_t end);

void check_request(const VirtualTexture& vt, const SampleRequest& r) {
    require(r.painting < vt.layout().paintings.size(), "painting out of range");
    require(r.u && r.v && r.out, "sample: missing arrays");
    require(r.uv_stride >= 1, "sample: uv_stride must be >= 1");
}
}  // namespace

void sample(const VirtualTexture& vt, const SampleRequest& r) {
    check_request(vt, r);
    const auto lock = vt.read_lock();
    parallel_for(r.count, 4096, [&](std::size_t b, std::size_t e) { sample_range(vt, r, b, e); },
                 r.threads);
}

void sample_serial(const VirtualTexture& vt, const SampleRequest& r) {
    check_request(vt, r);
    const auto lock = vt.read_lock();
    sample_range(vt, r, 0, r.count);
}

void sample_serial_locked(const VirtualTexture& vt, const SampleRequest& r) {
    check_request(vt, r);
    sample_range(vt, r, 0, r.count);
}

namespace {
// Tile column holding the tap's sample point: floor((i0 + 0.5 + f) / P) (i0 >= 0 after the
// clamp; 32-bit division is the cheaper one).
inline std::uint32_t tap_tile(const Tap& t, const Divider& P) {
    return P(static_cast<std::uint32_t>(t.i0 + (t.f >= 0.5f ? 1 : 0)));
}

// The 2 x 2 footprint at texel (jx, jy) of a BC1 tile as four palette words t00, t10, t01,
// t11, which bilerp_words blends exactly as bilerp_rgb8 blends an RGB8 slot holding the
// decoded tile. 9 footprints in 16 lie in one block, and neighbouring samples often share
// blocks: the last block's palette is kept and decoded again only for another block.
class Bc1Footprint {
public:
    explicit Bc1Footprint(std::uint32_t blocks_per_row) : blocks_per_row_(blocks_per_row) {}

    void quad(const std::uint8_t* tile, std::uint32_t jx, std::uint32_t jy, std::uint32_t* c) {
        const std::uint8_t* b = block_of(tile, jx, jy);
        const std::uint32_t* pal = palette(b);
        if ((jx & 3u) != 3u && (jy & 3u) != 3u) {
            c[0] = pal[index(b, jx, jy)], c[1] = pal[index(b, jx + 1, jy)];
            c[2] = pal[index(b, jx, jy + 1)], c[3] = pal[index(b, jx + 1, jy + 1)];
            return;
        }
        c[0] = pal[index(b, jx, jy)];
        const std::uint32_t xs[3] = {jx + 1, jx, jx + 1}, ys[3] = {jy, jy + 1, jy + 1};
        for (int k = 0; k < 3; ++k) {
            const std::uint8_t* bk = block_of(tile, xs[k], ys[k]);
            c[k + 1] = palette(bk)[index(bk, xs[k], ys[k])];
        }
    }

private:
    const std::uint8_t* block_of(const std::uint8_t* tile, std::uint32_t x, std::uint32_t y) const {
        return tile + (std::size_t(y >> 2) * blocks_per_row_ + (x >> 2)) * kBc1BlockBytes;
    }
    static std::uint32_t index(const std::uint8_t* block, std::uint32_t x, std::uint32_t y) {
        return (block[4 + (y & 3u)] >> (2 * (x & 3u))) & 3u;
    }
    // Valid while the cache is read-locked (the sampler holds the lock for the whole call).
    const std::uint32_t* palette(const std::uint8_t* block) {
        if (block != last_) bc1_palette(block, palette_), last_ = block;
        return palette_;
    }

    const std::uint32_t blocks_per_row_;
    const std::uint8_t* last_ = nullptr;
    std::uint32_t palette_[4] = {};
};

constexpr std::size_t kBatch = 64;
constexpr std::size_t kRun = 16;  // samples checked together for one tile (kBatch's divisor)

// Per sample of a batch: level-0 position, level asked for, the taps at that level (integer
// texel and weight per axis) and the tile column / row holding the sample point.
struct TapBatch {
    alignas(64) double x0[kBatch], y0[kBatch];
    alignas(64) std::int32_t ix[kBatch], iy[kBatch];
    alignas(64) float fx[kBatch], fy[kBatch];
    alignas(64) std::uint32_t level[kBatch], cx[kBatch], cy[kBatch];
};

// The tap loops' clamps as selects, so that GCC vectorises the loops: "0 < x ? x : 0" also
// maps NaN to 0. below_one clamps a non-negative double to 1 on its bits (non-negative doubles
// order as their int64 bits): as a double select it kept GCC 12 from vectorising the loop
// ("control flow in loop").
template <typename T>
inline T lo0(T x) { return T(0) < x ? x : T(0); }
template <typename T, typename U>
inline auto below(T x, U hi) { return x < hi ? x : hi; }
template <typename T, typename U>
inline auto above(T x, U lo) { return lo < x ? x : lo; }
inline double below_one(double x) {
    constexpr std::int64_t kOneBits = 0x3ff0000000000000;  // 1.0
    return std::bit_cast<double>(below(std::bit_cast<std::int64_t>(x), kOneBits));
}

// The sampler's per-sample arithmetic without branches and on restrict pointers, so GCC
// vectorises it; the same operations as sample_range's taps (bilinear_tap, tap_tile), hence
// the same results. Min and max are selects; "0 < x ? x : 0" also maps NaN to 0.
void bilinear_taps(const double* __restrict u_in, const double* __restrict v_in,
                   const float* __restrict lod_in, std::size_t n, const PyramidExtent e,
                   const Divider divide_p, TapBatch& __restrict b) {
    const std::uint32_t width = e.width, height = e.height;
    const double W = width, H = height;
    const float top = e.top;
    for (std::size_t k = 0; k < n; ++k) {
        const double u = below_one(lo0(u_in[k])), v = below_one(lo0(v_in[k]));
        const float lod = below(lo0(lod_in[k]), top);
        // lod >= 0 here, so lround(lod) = floor(lod + 0.5).
        const auto l = static_cast<std::uint32_t>(lod + 0.5f);
        const double x0 = u * W, y0 = v * H;
        // x0 2^-l exactly (2^-l from its exponent bits) and level l's extent, as LevelAxes
        // computes them.
        const double scale = std::bit_cast<double>(std::uint64_t(1023 - l) << 52);
        const std::uint32_t wl = (width + (1u << l) - 1) >> l;
        const std::uint32_t hl = (height + (1u << l) - 1) >> l;
        const double tx = below(above(x0 * scale, 0.5), double(wl) - 0.5) - 0.5;
        const double ty = below(above(y0 * scale, 0.5), double(hl) - 0.5) - 0.5;
        const auto i = static_cast<std::int32_t>(tx), j = static_cast<std::int32_t>(ty);
        const float f = static_cast<float>(tx - double(i)), g = static_cast<float>(ty - double(j));
        b.x0[k] = x0, b.y0[k] = y0, b.level[k] = l;
        b.ix[k] = i, b.iy[k] = j, b.fx[k] = f, b.fy[k] = g;
        // 0 <= i, j < 2^30 (a painting is at most 2^30 texels a side), so i + 1 < 2^31.
        b.cx[k] = divide_p.by_double_below_2_31(i + (f >= 0.5f ? 1 : 0));
        b.cy[k] = divide_p.by_double_below_2_31(j + (g >= 0.5f ? 1 : 0));
    }
}
// The bilinear blends of n RGB8 footprints (texel[k], weights fx[k], fy[k]) into out[3k..];
// four-float stores overlap the next sample's first channel, which is written after, so the
// last sample is stored wide only when more_after (another thread may own the next sample).
inline void bilerp_rgb8_run(const std::uint8_t* const* texel, std::size_t row, const float* fx,
                            const float* fy, std::size_t n, bool more_after, float* out) {
    std::size_t k = 0;
#if defined(__SSE2__)
    for (; k + 1 < n || (k < n && more_after); ++k) bilerp_rgb8_wide(texel[k], row, fx[k], fy[k], out + 3 * k);
#else
    (void)more_after;
#endif
    for (; k < n; ++k) bilerp_rgb8(texel[k], row, 3, 1, fx[k], fy[k], out + 3 * k);
}

// VT-mobile-VR eqs (3)-(10), in the form that stays exact. Eq (3,4) scale the painting's uv into
// its padded page table and eq (5,6) normalise by the merged table; we instead keep the
// level-0 texel position x0 = u W in double, derive the level-l position x0 2^-l exactly, and
// index the table by the integer tile column floor(x / P) (+ the painting's offset >> l,
// inside PageTable). Eq (7,8)'s in-tile offset with border E becomes the integer texel
// i0 - tx P + E plus the fraction, and eq (9,10)'s physical coordinate the slot's texel
// origin plus that: no normalised float coordinate ever exists, so 1/256 texel holds at u
// near 1 on the widest painting.
void sample_range(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin, std::size_t end) {
    if (r.filter == Filter::Bilinear) {
        if (vt.format() == TexelFormat::Bc1)
            sample_bilinear<TexelFormat::Bc1>(vt, r, begin, end);
        else
            sample_bilinear<TexelFormat::Rgb8>(vt, r, begin, end);
        return;
    }
    if (vt.format() == TexelFormat::Bc1)
        sample_trilinear<TexelFormat::Bc1>(vt, r, begin, end);
    else
        sample_trilinear_rgb8(vt, r, begin, end);
}

// The per-sample trilinear path: the reference that sample_trilinear's batches reproduce
// (tests compare the two).
void sample_trilinear_serial(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin,
                             std::size_t end) {
    const PaintingGeometry& pt = vt.layout().paintings[r.painting];
    const std::uint32_t L = pt.levels();
    const LevelAxes axes(pt.width(), pt.height(), L);
    const Divider divide_p(vt.layout().payload());
    TexelFinder finder(vt, r.painting);
    const bool bc1 = vt.format() == TexelFormat::Bc1;
    Bc1Footprint bc1_footprint(vt.layout().tile_size / 4);

    // Bilinear sample at level l with page-table fallback; returns the level that answered.
    auto bilinear = [&](double x0, double y0, std::uint32_t l, float* out)
                        __attribute__((always_inline)) -> std::uint32_t {
        Tap tx = axes.tap_x(x0, l), ty = axes.tap_y(y0, l);
        const std::uint32_t cx = tap_tile(tx, divide_p), cy = tap_tile(ty, divide_p);
        const PageEntry e = finder.entry(l, cx, cy);
        const std::uint32_t al = e.level(), s = al - l;
        if (s != 0) {  // fallback: the resident ancestor answers at its own resolution
            tx = axes.tap_x(x0, al);
            ty = axes.tap_y(y0, al);
        }
        if (bc1) {
            std::uint32_t jx, jy;
            const std::uint8_t* tile = finder.footprint(e, s, tx.i0, ty.i0, cx, cy, jx, jy);
            std::uint32_t quad[4];
            bc1_footprint.quad(tile, jx, jy, quad);
            bilerp_words(quad, tx.f, ty.f, out);
        } else {
            bilerp_rgb8(finder.texel(e, s, tx.i0, ty.i0, cx, cy), finder.row_bytes(), 3, 1, tx.f,
                        ty.f, out);
        }
        return al;
    };

    for (std::size_t i = begin; i < end; ++i) {
        const double ui = r.u[i * r.uv_stride], vi = r.v[i * r.uv_stride];
        const double u = std::isnan(ui) ? 0.0 : std::clamp(ui, 0.0, 1.0);
        const double v = std::isnan(vi) ? 0.0 : std::clamp(vi, 0.0, 1.0);
        const double x0 = u * pt.width(), y0 = v * pt.height();
        float lod = r.lod ? r.lod[i] : r.lod_scalar;
        lod = std::isnan(lod) ? 0.0f : std::clamp(lod, 0.0f, float(L - 1));
        float* out = r.out + 3 * i;
        const std::uint32_t l0 = static_cast<std::uint32_t>(lod);
        const float f = lod - float(l0);
        std::uint32_t answered = bilinear(x0, y0, l0, out);
        if (f > 0 && l0 + 1 < L) {
            float c[3];
            bilinear(x0, y0, l0 + 1, c);
            for (int k = 0; k < 3; ++k) out[k] += f * (c[k] - out[k]);
        }
        if (r.level_out) r.level_out[i] = static_cast<std::int8_t>(answered);
    }
}

// The same arithmetic as the trilinear path's bilinear taps, in batches and three passes,
// because the samples' texel reads are scattered over the physical texture and each used to
// wait for its cache miss: (1) per sample, branch-free so it vectorises, the level and the
// taps and tile at that level; (2) the page-table lookup (reused while samples stay in one
// tile), the fallback to a resident ancestor, the texel address, and a prefetch of both
// rows; (3) the blends, whose reads the prefetches have mostly brought in by then.
// For BC1 slots, (2) prefetches the footprint's first and last blocks and (3) decodes the
// footprint's four texels before the same blend.
template <TexelFormat F>
void sample_bilinear(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin, std::size_t end) {
    const PaintingGeometry& pt = vt.layout().paintings[r.painting];
    const std::uint32_t L = pt.levels(), width = pt.width(), height = pt.height();
    const LevelAxes axes(width, height, L);
    const Divider divide_p(vt.layout().payload());
    TexelFinder finder(vt, r.painting);
    const std::size_t row = finder.row_bytes();
    const std::uint32_t blocks_per_row = vt.layout().tile_size / 4;
    Bc1Footprint bc1_footprint(blocks_per_row);

    TapBatch b;
    const std::uint8_t* texel[kBatch];
    std::uint32_t jx_of[kBatch], jy_of[kBatch];
    float lod_scalar[kBatch];
    double u_dense[kBatch], v_dense[kBatch];
    std::fill(lod_scalar, lod_scalar + kBatch, r.lod_scalar);
    const PyramidExtent pyramid{width, height, float(L - 1)};

    for (std::size_t b0 = begin; b0 < end; b0 += kBatch) {
        const std::size_t n = std::min(kBatch, end - b0);
        // (1)
        const float* l_in = r.lod ? r.lod + b0 : lod_scalar;
        const double *u_in = r.u + b0, *v_in = r.v + b0;
        if (r.uv_stride != 1) {  // gathered here so the tap loop stays contiguous
            const std::size_t st = r.uv_stride;
            for (std::size_t k = 0; k < n; ++k)
                u_dense[k] = r.u[(b0 + k) * st], v_dense[k] = r.v[(b0 + k) * st];
            u_in = u_dense, v_in = v_dense;
        }
        bilinear_taps(u_in, v_in, l_in, n, pyramid, divide_p, b);
        // (2)
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint32_t l = b.level[k], cx = b.cx[k], cy = b.cy[k];
            const PageEntry e = finder.entry(l, cx, cy);
            const std::uint32_t al = e.level(), s = al - l;
            std::int64_t i = b.ix[k], j = b.iy[k];
            if (s != 0) {  // fallback: the resident ancestor answers at its own resolution
                const Tap tx = axes.tap_x(b.x0[k], al), ty = axes.tap_y(b.y0[k], al);
                i = tx.i0, j = ty.i0, b.fx[k] = tx.f, b.fy[k] = ty.f;
            }
            if constexpr (F == TexelFormat::Bc1) {
                std::uint32_t jx, jy;
                const std::uint8_t* tile = finder.footprint(e, s, i, j, cx, cy, jx, jy);
                __builtin_prefetch(tile + (std::size_t(jy >> 2) * blocks_per_row + (jx >> 2)) * kBc1BlockBytes);
                __builtin_prefetch(tile + (std::size_t((jy + 1) >> 2) * blocks_per_row + ((jx + 1) >> 2)) *
                                              kBc1BlockBytes);
                texel[k] = tile, jx_of[k] = jx, jy_of[k] = jy;
            } else {
                const std::uint8_t* p = finder.texel(e, s, i, j, cx, cy);
                __builtin_prefetch(p);
                __builtin_prefetch(p + row);
                texel[k] = p;
            }
            if (r.level_out) r.level_out[b0 + k] = static_cast<std::int8_t>(al);
        }
        // (3)
        float* out = r.out + 3 * b0;
        if constexpr (F == TexelFormat::Bc1) {
            for (std::size_t k = 0; k < n; ++k) {
                std::uint32_t quad[4];
                bc1_footprint.quad(texel[k], jx_of[k], jy_of[k], quad);
                bilerp_words(quad, b.fx[k], b.fy[k], out + 3 * k);
            }
        } else {
            bilerp_rgb8_run(texel, row, b.fx, b.fy, n, b0 + n < end, out);
        }
    }
}

// Trilinear as two batched bilinear passes (sample_bilinear's prefetching batches) at
// floor(lod) and floor(lod) + 1, blended as the per-sample path blends them: the same taps,
// the same fallback, the same blend, so the same results.
template <TexelFormat F>
void sample_trilinear(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin, std::size_t end) {
    const std::uint32_t L = vt.layout().paintings[r.painting].levels();
    constexpr std::size_t kChunk = 256;
    float fine[kChunk], coarse[kChunk], blend[kChunk], second[3 * kChunk], lod_scalar[kChunk];
    std::fill(lod_scalar, lod_scalar + kChunk, r.lod_scalar);
    const float top = float(L - 1);
    const std::int32_t levels = std::int32_t(L);
    for (std::size_t b = begin; b < end; b += kChunk) {
        const std::size_t n = std::min(kChunk, end - b);
        const float* __restrict lod_in = r.lod ? r.lod + b : lod_scalar;
        // Branch-free so it vectorises, levels as int32 (below 32; x86 has no SIMD uint32
        // to float below AVX-512).
        std::int32_t any = 0;
        for (std::size_t k = 0; k < n; ++k) {
            float lod = lod_in[k];
            // isnan ? 0 : clamp(lod, 0, top) as selects ("0 < x ? x : 0" maps NaN to 0; -0
            // becomes +0, the same level and blend).
            lod = 0.0f < lod ? lod : 0.0f;
            lod = lod < top ? lod : top;
            const std::int32_t l0 = static_cast<std::int32_t>(lod);
            const float f = lod - float(l0);
            const bool two = (f > 0) & (l0 + 1 < levels);
            fine[k] = float(l0), coarse[k] = float(two ? l0 + 1 : l0), blend[k] = two ? f : 0.0f;
            any |= std::int32_t(two);
        }
        SampleRequest q = r;
        q.u = r.u + b * r.uv_stride, q.v = r.v + b * r.uv_stride;
        q.lod = fine, q.count = n, q.filter = Filter::Bilinear;
        q.out = r.out + 3 * b;
        q.level_out = r.level_out ? r.level_out + b : nullptr;
        sample_bilinear<F>(vt, q, 0, n);
        if (!any) continue;
        q.lod = coarse, q.out = second, q.level_out = nullptr;
        sample_bilinear<F>(vt, q, 0, n);
        // Branch-free so it vectorises: where blend is 0 the sum adds a zero (second is the
        // same level's finite value there), which leaves every value as it was.
        float* __restrict out = r.out + 3 * b;
        for (std::size_t k = 0; k < n; ++k)
            for (int c = 0; c < 3; ++c)
                out[3 * k + c] += blend[k] * (second[3 * k + c] - out[3 * k + c]);
    }
}


// Trilinear on RGB8 slots in one pass over the samples instead of two bilinear passes and a
// blend: both levels' taps from one clamped uv (trilinear_taps), each level's page entry
// kept by its own finder (one finder for both would thrash between the two levels' tiles),
// and where a level's tile is resident (no fallback, nearly always) the footprint's in-tile
// byte offset computed in the taps' lanes, so the per-sample loop only adds the slot's base.
// The same taps, fallback, blend products and blend as sample_trilinear, hence the same
// floats: a sample with one level (blend 0) blends its fine footprint with itself, which
// adds 0 * 0, as sample_trilinear's blend adds 0 * (second - out) with second = out.
struct TrilinearBatch {
    alignas(64) double x0[kBatch], y0[kBatch];
    alignas(64) std::int32_t offset[2][kBatch];
    alignas(64) float fx[2][kBatch], fy[2][kBatch], blend[kBatch];
    alignas(64) std::uint32_t level[2][kBatch], cx[2][kBatch], cy[2][kBatch];
};

// bilinear_taps for the fine level floor(lod) and the coarse level floor(lod) + 1 (or the
// fine one again where trilinear blends nothing), with sample_trilinear's level rule, plus
// each level's in-tile offset for a resident tile: TexelFinder::footprint with s = 0,
// in int32 (i, j < 2^30 and cx P <= i + 1).
// Returns whether any sample blends two levels; if none does, the coarse level's taps are not
// computed (nobody reads them).
// Not inlined: inlined, its restrict parameters were lost and GCC ran a scalar copy of the
// first loop with branches for a large share of the samples.
__attribute__((noinline)) bool trilinear_taps(const double* __restrict u_in,
                                              const double* __restrict v_in,
                                              const float* __restrict lod_in, std::size_t n,
                                              const PyramidExtent e, const std::int32_t levels,
                                              const Divider divide_p, const TileExtent t,
                                              TrilinearBatch& __restrict b) {
    const std::uint32_t width = e.width, height = e.height;
    const double W = width, H = height;
    const float top = e.top;
    const std::int32_t P = t.payload, E = t.border, last = t.tile - 2, row = t.row_bytes;
    // The levels and the blend (sample_trilinear's rule), then the level-0 positions: apart,
    // as one loop GCC did not vectorise ("control flow in loop").
    std::uint32_t any_two = 0;
    for (std::size_t k = 0; k < n; ++k) {
        const float lod = below(lo0(lod_in[k]), top);
        const std::int32_t l0 = static_cast<std::int32_t>(lod);
        const float f = lod - float(l0);
        const bool two = (f > 0) & (l0 + 1 < levels);
        b.blend[k] = two ? f : 0.0f;
        b.level[0][k] = std::uint32_t(l0), b.level[1][k] = std::uint32_t(two ? l0 + 1 : l0);
        any_two |= std::uint32_t(two);
    }
    for (std::size_t k = 0; k < n; ++k) {
        b.x0[k] = below_one(lo0(u_in[k])) * W, b.y0[k] = below_one(lo0(v_in[k])) * H;
    }
    // One loop per level, as bilinear_taps (a loop over both levels inside did not vectorise).
    for (int c = 0; c < (any_two ? 2 : 1); ++c) {
        const std::uint32_t* __restrict level = b.level[c];
        for (std::size_t k = 0; k < n; ++k) {
            const std::uint32_t l = level[k];
            const double scale = std::bit_cast<double>(std::uint64_t(1023 - l) << 52);
            const std::uint32_t wl = (width + (1u << l) - 1) >> l;
            const std::uint32_t hl = (height + (1u << l) - 1) >> l;
            const double tx = below(above(b.x0[k] * scale, 0.5), double(wl) - 0.5) - 0.5;
            const double ty = below(above(b.y0[k] * scale, 0.5), double(hl) - 0.5) - 0.5;
            const auto i = static_cast<std::int32_t>(tx), j = static_cast<std::int32_t>(ty);
            const float fi = static_cast<float>(tx - double(i)), gj = static_cast<float>(ty - double(j));
            const auto cx = static_cast<std::int32_t>(divide_p.by_double_below_2_31(i + (fi >= 0.5f ? 1 : 0)));
            const auto cy = static_cast<std::int32_t>(divide_p.by_double_below_2_31(j + (gj >= 0.5f ? 1 : 0)));
            const std::int32_t jx = below(above(i - cx * P + E, 0), last);
            const std::int32_t jy = below(above(j - cy * P + E, 0), last);
            b.fx[c][k] = fi, b.fy[c][k] = gj;
            b.cx[c][k] = std::uint32_t(cx), b.cy[c][k] = std::uint32_t(cy);
            b.offset[c][k] = jy * row + jx * 3;
        }
    }
    return any_two != 0;
}

void sample_trilinear_rgb8(const VirtualTexture& vt, const SampleRequest& r, std::size_t begin,
                           std::size_t end) {
    const PaintingGeometry& pt = vt.layout().paintings[r.painting];
    const std::uint32_t L = pt.levels(), width = pt.width(), height = pt.height();
    const LevelAxes axes(width, height, L);
    const Divider divide_p(vt.layout().payload());
    TexelFinder finders[2] = {TexelFinder(vt, r.painting), TexelFinder(vt, r.painting)};
    const std::size_t row = finders[0].row_bytes();
    const std::uint8_t* const physical = vt.physical();
    const std::size_t slot_bytes = vt.slot_bytes();
    const TileExtent tile{std::int32_t(vt.layout().payload()), std::int32_t(vt.layout().border),
                          std::int32_t(vt.layout().tile_size), std::int32_t(row)};
    const PyramidExtent pyramid{width, height, float(L - 1)};

    TrilinearBatch b;
    const std::uint8_t* texel[2][kBatch];
    float lod_scalar[kBatch], lod_dense[kBatch];
    double u_dense[kBatch], v_dense[kBatch];
    std::fill(lod_scalar, lod_scalar + kBatch, r.lod_scalar);

    for (std::size_t b0 = begin; b0 < end; b0 += kBatch) {
        const std::size_t n = std::min(kBatch, end - b0);
        const float* l_in = r.lod ? r.lod + b0 : lod_scalar;
        const double *u_in = r.u + b0, *v_in = r.v + b0;
        // The taps in whole vectors of 8 (no scalar remainder loop): a partial batch and
        // interleaved (u, v) are copied, the partial batch padded with valid inputs whose
        // taps nobody reads.
        const std::size_t n8 = (n + 7) & ~std::size_t(7);
        if (r.uv_stride != 1 || n8 != n) {
            const std::size_t st = r.uv_stride;
            for (std::size_t k = 0; k < n; ++k)
                u_dense[k] = r.u[(b0 + k) * st], v_dense[k] = r.v[(b0 + k) * st], lod_dense[k] = l_in[k];
            std::fill(u_dense + n, u_dense + n8, 0.0);
            std::fill(v_dense + n, v_dense + n8, 0.0);
            std::fill(lod_dense + n, lod_dense + n8, 0.0f);
            u_in = u_dense, v_in = v_dense, l_in = lod_dense;
        }
        // A batch whose samples all take one level (a magnified or exactly mip-matched
        // painting: a close look) reads, addresses and blends the fine level only; its blend
        // would add 0 x 0 to every value.
        const int levels = trilinear_taps(u_in, v_in, l_in, n8, pyramid, std::int32_t(L), divide_p, tile, b) ? 2 : 1;
        // Page entries, fallbacks, addresses and prefetches of the levels used. A run of 16
        // samples whose taps lie in one resident tile at each level (the common case: the
        // display's samples are neighbouring pixels) takes its slots' bases once, in a loop
        // that vectorises; the others sample by sample.
        for (std::size_t k0 = 0; k0 < n; k0 += kRun) {
            const std::size_t k1 = std::min(n, k0 + kRun);
            const std::uint8_t* base[2] = {nullptr, nullptr};
            for (int c = 0; c < levels && k1 - k0 == kRun; ++c) {
                const std::uint32_t l = b.level[c][k0], cx = b.cx[c][k0], cy = b.cy[c][k0];
                std::uint32_t differ = 0;
                for (std::size_t k = k0; k < k1; ++k)
                    differ |= (b.level[c][k] ^ l) | (b.cx[c][k] ^ cx) | (b.cy[c][k] ^ cy);
                if (differ) break;
                const PageEntry e = finders[c].entry(l, cx, cy);
                if (e.level() != l) break;  // a fallback (or no entry)
                base[c] = physical + std::size_t(e.slot()) * slot_bytes;
            }
            if (base[0] && (levels == 1 || base[1])) {
                for (int c = 0; c < levels; ++c) {
                    const std::int32_t* __restrict offset = b.offset[c];
                    const std::uint8_t** __restrict out = texel[c];
                    for (std::size_t k = k0; k < k1; ++k) out[k] = base[c] + std::uint32_t(offset[k]);
                    for (std::size_t k = k0; k < k1; k += 4) {  // 4 texels of 3 bytes: under a line
                        __builtin_prefetch(out[k]);
                        __builtin_prefetch(out[k] + row);
                    }
                }
                if (r.level_out)
                    std::fill(r.level_out + b0 + k0, r.level_out + b0 + k1, static_cast<std::int8_t>(b.level[0][k0]));
                continue;
            }
            for (std::size_t k = k0; k < k1; ++k) {
                for (int c = 0; c < levels; ++c) {
                    const std::uint32_t l = b.level[c][k], cx = b.cx[c][k], cy = b.cy[c][k];
                    const PageEntry e = finders[c].entry(l, cx, cy);
                    const std::uint32_t al = e.level(), s = al - l;
                    const std::uint8_t* p;
                    if (s == 0) [[likely]] {
                        p = physical + std::size_t(e.slot()) * slot_bytes + std::uint32_t(b.offset[c][k]);
                    } else {  // fallback: the resident ancestor answers at its own resolution
                        const Tap tx = axes.tap_x(b.x0[k], al), ty = axes.tap_y(b.y0[k], al);
                        b.fx[c][k] = tx.f, b.fy[c][k] = ty.f;
                        p = finders[c].texel(e, s, tx.i0, ty.i0, cx, cy);
                    }
                    __builtin_prefetch(p);
                    __builtin_prefetch(p + row);
                    texel[c][k] = p;
                    if (c == 0 && r.level_out) r.level_out[b0 + k] = static_cast<std::int8_t>(al);
                }
            }
        }
        float* out = r.out + 3 * b0;
        if (levels == 1) {  // blend_levels_rgb8's fine half: the same products in the same order
            bilerp_rgb8_run(texel[0], row, b.fx[0], b.fy[0], n, b0 + n < end, out);
            continue;
        }
        for (std::size_t k = 0; k < n; ++k)
            blend_levels_rgb8(texel[0][k], texel[1][k], row, b.fx[0][k], b.fy[0][k], b.fx[1][k],
                              b.fy[1][k], b.blend[k], b0 + k + 1 < end, out + 3 * k);
    }
}

}  // namespace

void sample_trilinear_reference(const VirtualTexture& vt, const SampleRequest& r) {
    check_request(vt, r);
    const auto lock = vt.read_lock();
    sample_trilinear_serial(vt, r, 0, r.count);
}

}  // namespace gigascroll
