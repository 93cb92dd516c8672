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

// What both sampling paths do once a sample's tile is known: its page-table entry (looked up
// again only when a sample leaves the last tile; neighbours mostly share it) and the
// physical address of a texel of the tile that answered.
class TexelFinder {
public:
    TexelFinder(const VirtualTexture& vt, std::uint32_t painting)
        : table_(vt.page_table()), painting_(painting), physical_(vt.physical()),
          P_(table_.layout().payload()), E_(table_.layout().border), T_(table_.layout().tile_size),
          tile_bytes_(vt.slot_bytes()) {}

    std::size_t row_bytes() const { return std::size_t(T_) * 3; }

    // Forgets the last entry (the next lookup reads the table: its residency may be new).
    void forget() { last_l_ = ~0u; }

    // Entry of tile (cx, cy) at level l: the level and slot of its finest resident ancestor.
    PageEntry entry(std::uint32_t l, std::uint32_t cx, std::uint32_t cy) {
        if (l != last_l_ || cx != last_cx_ || cy != last_cy_)
            last_l_ = l, last_cx_ = cx, last_cy_ = cy, last_ = table_.lookup(painting_, l, cx, cy);
        return last_;
    }

    // Texel (i, j) of e's level, where e answers tile (cx, cy) from s levels coarser:
    // eq (7,8)'s in-tile offset with the border, clamped so the 2 x 2 footprint stays inside.
    const std::uint8_t* texel(PageEntry e, std::uint32_t s, std::int64_t i, std::int64_t j,
                              std::uint32_t cx, std::uint32_t cy) const {
        std::uint32_t jx, jy;
        const std::uint8_t* tile = footprint(e, s, i, j, cx, cy, jx, jy);
        return tile + jy * row_bytes() + jx * 3;
    }

    // The same for any slot format: the slot's first byte and the in-tile texel (jx, jy).
    const std::uint8_t* footprint(PageEntry e, std::uint32_t s, std::int64_t i, std::int64_t j,
                                  std::uint32_t cx, std::uint32_t cy, std::uint32_t& jx,
                                  std::uint32_t& jy) const {
        jx = std::uint32_t(std::clamp<std::int64_t>(i - std::int64_t(cx >> s) * P_ + E_, 0, T_ - 2));
        jy = std::uint32_t(std::clamp<std::int64_t>(j - std::int64_t(cy >> s) * P_ + E_, 0, T_ - 2));
        return physical_ + std::size_t(e.slot()) * tile_bytes_;
    }

private:
    const PageTable& table_;
    const std::uint32_t painting_;
    const std::uint8_t* const physical_;
    const std::int64_t P_, E_, T_;
    const std::size_t tile_bytes_;
    std::uint32_t last_l_ = ~0u, last_cx_ = 0, last_cy_ = 0;
    PageEntry last_;
};

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

struct PyramidExtent {
    std::uint32_t width, height;  // level 0, texels
    float top;                    // the coarsest level
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

struct TileExtent {
    std::int32_t payload, border, tile, row_bytes;
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

// Both levels' bilerp_rgb8 of one sample and sample_trilinear's blend, out[0..2]; `wide`
// also writes a garbage out[3] (the next sample's first channel, written after).
inline void blend_levels_rgb8(const std::uint8_t* fine, const std::uint8_t* coarse, std::size_t row,
                              float fx0, float fy0, float fx1, float fy1, float blend, bool wide,
                              float* out) {
#if defined(__AVX2__)
    // The two footprints in the two halves of 8 lanes: the same products and sums per half.
    auto texels = [](const std::uint8_t* a, const std::uint8_t* b) {
        std::int32_t x, y;
        std::memcpy(&x, a, 4);
        std::memcpy(&y, b, 4);
        return _mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_insert_epi32(_mm_cvtsi32_si128(x), y, 1)));
    };
    auto halves = [](float a, float b) {
        return _mm256_insertf128_ps(_mm256_castps128_ps256(_mm_set1_ps(a)), _mm_set1_ps(b), 1);
    };
    const __m256 one = _mm256_set1_ps(1.0f), fx = halves(fx0, fx1), fy = halves(fy0, fy1);
    const __m256 gx = _mm256_sub_ps(one, fx), gy = _mm256_sub_ps(one, fy);
    __m256 c = _mm256_mul_ps(_mm256_mul_ps(gx, gy), texels(fine, coarse));
    c = _mm256_add_ps(c, _mm256_mul_ps(_mm256_mul_ps(fx, gy), texels(fine + 3, coarse + 3)));
    c = _mm256_add_ps(c, _mm256_mul_ps(_mm256_mul_ps(gx, fy), texels(fine + row, coarse + row)));
    c = _mm256_add_ps(c, _mm256_mul_ps(_mm256_mul_ps(fx, fy), texels(fine + row + 3, coarse + row + 3)));
    const __m128 f = _mm256_castps256_ps128(c), g = _mm256_extractf128_ps(c, 1);
    const __m128 r = _mm_add_ps(f, _mm_mul_ps(_mm_set1_ps(blend), _mm_sub_ps(g, f)));
    if (wide) {
        _mm_storeu_ps(out, r);
    } else {
        alignas(16) float lanes[4];
        _mm_store_ps(lanes, r);
        out[0] = lanes[0], out[1] = lanes[1], out[2] = lanes[2];
    }
#elif defined(__SSE2__)
    (void)wide;
    alignas(16) float f[4], g[4];
    bilerp_rgb8_wide(fine, row, fx0, fy0, f);
    bilerp_rgb8_wide(coarse, row, fx1, fy1, g);
    for (int k = 0; k < 3; ++k) out[k] = f[k] + blend * (g[k] - f[k]);
#else
    (void)wide;
    float c[3];
    bilerp_rgb8(fine, row, 3, 1, fx0, fy0, out);
    bilerp_rgb8(coarse, row, 3, 1, fx1, fy1, c);
    for (int k = 0; k < 3; ++k) out[k] += blend * (c[k] - out[k]);
#endif
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

// sample_trilinear_rgb8 for a packet of 16 samples in one or two resident tiles per level, all
// in 16 lanes: trilinear_taps' level rule and taps (in float from the packet's origin, see
// sample16), the texels at the same addresses (the 4-byte words of each footprint's corners),
// and blend_levels_rgb8's bilinear blends and blend of the levels. A sample that blends
// nothing (blend 0) takes its coarse taps at its fine level (as trilinear_taps leaves them)
// and adds 0 x (g - f) to f; so only the samples that blend two levels must share the
// coarse tile.
#if defined(__AVX512F__)
// GCC 12 warns that the _mm512_undefined_* sources inside its own AVX-512 intrinsics may be
// used uninitialized (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"  // the same, in _mm512_reduce_*_epi32
namespace {
// One level's taps for 16 lanes (trilinear_taps' second loop): weights, tile and in-tile
// byte offset.
struct LevelTaps {
    __m512 fx, fy;
    __m512i level, cx, cy, row, offset;  // row: the footprint's first texel row in its tile
};
// trilinear_taps' level rule: each lane's fine level l0 (lo0 is max with 0 second, which
// maps NaN to 0 as the select does; below is min), which lanes blend two levels and their
// weight.
struct LaneLevels {
    __m512i l0;
    __mmask16 blending;
    __m512 blend;
};
inline LaneLevels lane_levels(const float* lod, float top, std::int32_t levels) {
    const __m512 zero = _mm512_setzero_ps();
    const __m512 lod_c = _mm512_min_ps(_mm512_max_ps(_mm512_loadu_ps(lod), zero), _mm512_set1_ps(top));
    LaneLevels v;
    v.l0 = _mm512_cvttps_epi32(lod_c);
    const __m512 frac = _mm512_sub_ps(lod_c, _mm512_cvtepi32_ps(v.l0));
    v.blending = _mm512_cmp_ps_mask(frac, zero, _CMP_GT_OQ) &
                 _mm512_cmplt_epi32_mask(_mm512_add_epi32(v.l0, _mm512_set1_epi32(1)), _mm512_set1_epi32(levels));
    v.blend = _mm512_maskz_mov_ps(v.blending, frac);
    return v;
}
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
}  // namespace
#endif

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
#if defined(__AVX512F__)
    // The samples from their fine and (for the lanes in levels.blending) coarse taps: each
    // level's tiles, texels and bilinear blend, then the blend of the two levels.
    bool sample(const LevelTaps& fine_taps, const LevelTaps& coarse_taps, const LaneLevels& levels,
                float* r, float* g, float* b);
    // sample16's stretches of a level's pair of texel rows (see there) for a packet across a
    // tile's edge: lane 0's tile last_tile[finder] (tile x0 in lane coordinates x0_lanes,
    // in_tile its lanes) and its neighbour, into rows[r] = {bytes 0-63, 64-127}. False when
    // the other lanes are not all in the payload of the neighbour on one side or it is not
    // resident.
    bool across_edge(int level, int finder, __m512i nx_lanes, std::int32_t x0_lanes, __mmask16 in_tile,
                     std::int32_t lo, std::int32_t span, std::size_t row_start, __m512i (&rows)[2][2]);
#endif
};

TrilinearLanes::TrilinearLanes(const VirtualTexture& vt, std::uint32_t painting) {
#if defined(__AVX512F__)
    // Disabled for a painting the texture does not hold: sample() says so.
    if (vt.format() == TexelFormat::Rgb8 && painting < vt.layout().paintings.size())
        state_ = std::make_unique<State>(vt, painting);
#else
    (void)vt, (void)painting;  // no lanes to sample in: always disabled
#endif
}
void TrilinearLanes::forget_tiles() {
    if (!state_) return;
    for (TexelFinder& f : state_->finders) f.forget();
    for (State::LastTile& t : state_->last_tile) t.level = -1;
}
TrilinearLanes::~TrilinearLanes() = default;
TrilinearLanes::TrilinearLanes(TrilinearLanes&&) noexcept = default;

#if defined(__AVX512F__)
bool TrilinearLanes::State::sample(const LevelTaps& fine_taps, const LevelTaps& coarse_taps,
                                   const LaneLevels& lv, float* r, float* g, float* b) {
    State& st = *this;
    const __mmask16 blending = lv.blending;
    const __m512 blend = lv.blend;
    const TileExtent t = st.tile;
    // The tiles of the lanes in mask at their level: the first lane's and, for a packet across a
    // tile edge, one other, each resident (its slot) with the lanes it holds; false for a third
    // tile or a tile that is not resident (a fallback).
    struct LevelTiles {
        const std::uint8_t* base[2];
        __mmask16 lanes[2];
        int count;
    };
    auto tiles = [&](const LevelTaps& lt, int c, __mmask16 mask, LevelTiles& out) {
        out.count = 0;
        for (int k = 0; k < 2 && mask; ++k) {
            auto first = [&](__m512i x) {  // the value of mask's first lane (lane 0 nearly always)
                return std::uint32_t(_mm_cvtsi128_si32(_mm512_castsi512_si128(
                    mask & 1 ? x : _mm512_maskz_compress_epi32(mask, x))));
            };
            const std::uint32_t l = first(lt.level), cx = first(lt.cx), cy = first(lt.cy);
            const __mmask16 same = _mm512_mask_cmpeq_epi32_mask(mask, lt.level, _mm512_set1_epi32(int(l))) &
                                   _mm512_mask_cmpeq_epi32_mask(mask, lt.cx, _mm512_set1_epi32(int(cx))) &
                                   _mm512_mask_cmpeq_epi32_mask(mask, lt.cy, _mm512_set1_epi32(int(cy)));
            out.base[k] = st.base(2 * c + k, l, cx, cy);
            if (!out.base[k]) return false;
            out.lanes[k] = same, out.count = k + 1;
            mask &= ~same;
        }
        return mask == 0;
    };
    LevelTiles fine, coarse;
    if (!tiles(fine_taps, 0, 0xFFFF, fine)) return false;
    if (blending && !tiles(coarse_taps, 1, blending, coarse)) return false;
    const std::int32_t row = t.row_bytes;
    // The 4-byte words at each lane's footprint corners (offset, + 3, + row, + row + 3: the
    // texel and its right neighbour in two rows), q[0..3]. When the lanes in mask share the
    // footprint's texel rows and their corners span at most 128 bytes (nearly always: a
    // packet of neighbouring pixels reads one stretch of two rows), the two stretches are
    // loaded (masked to the bytes the gathers would read) and the words picked out with byte
    // permutes; otherwise gathered. The lanes outside mask get some word of the stretch.
    auto corners = [&](const LevelTaps& lt, const std::uint8_t* base, __mmask16 mask, __m512i (&q)[4]) {
#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
        const int lo = _mm512_mask_reduce_min_epi32(mask, lt.offset);
        const int hi = _mm512_mask_reduce_max_epi32(mask, lt.offset);
        const int span = hi - lo + 7;  // bytes lo .. hi + 6
        const int first_row = _mm_cvtsi128_si32(_mm512_castsi512_si128(mask & 1 ? lt.row : _mm512_maskz_compress_epi32(mask, lt.row)));
        if (span <= 128 && !_mm512_mask_cmpneq_epi32_mask(mask, lt.row, _mm512_set1_epi32(first_row))) {
            const __m512i rel = _mm512_maskz_sub_epi32(mask, lt.offset, _mm512_set1_epi32(lo));
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
            return;
        }
#else
        (void)mask;
#endif
        const std::int32_t delta[4] = {0, 3, row, row + 3};
        for (int k = 0; k < 4; ++k)
            q[k] = _mm512_i32gather_epi32(_mm512_add_epi32(lt.offset, _mm512_set1_epi32(delta[k])),
                                          static_cast<const void*>(base), 1);
    };
    // One level's bilinear blend: channels R, G, B of 16 lanes.
    auto bilinear = [&](const LevelTaps& lt, const LevelTiles& lv, __m512& R, __m512& G, __m512& B)
                        __attribute__((always_inline)) {
        const __m512 one = _mm512_set1_ps(1.0f);
        const __m512 fx = lt.fx, fy = lt.fy;
        const __m512 gx = _mm512_sub_ps(one, fx), gy = _mm512_sub_ps(one, fy);
        const __m512i byte = _mm512_set1_epi32(0xff);
        const __m512 w[4] = {_mm512_mul_ps(gx, gy), _mm512_mul_ps(fx, gy), _mm512_mul_ps(gx, fy),
                             _mm512_mul_ps(fx, fy)};
        __m512i words[4];
        corners(lt, lv.base[0], lv.lanes[0], words);
        if (lv.count == 2) {  // the lanes in the other tile
            __m512i other[4];
            corners(lt, lv.base[1], lv.lanes[1], other);
            for (int q = 0; q < 4; ++q) words[q] = _mm512_mask_mov_epi32(words[q], lv.lanes[1], other[q]);
        }
        for (int q = 0; q < 4; ++q) {
            const __m512i texel = words[q];
            const __m512 tr = _mm512_cvtepi32_ps(_mm512_and_si512(texel, byte));
            const __m512 tg = _mm512_cvtepi32_ps(_mm512_and_si512(_mm512_srli_epi32(texel, 8), byte));
            const __m512 tb = _mm512_cvtepi32_ps(_mm512_and_si512(_mm512_srli_epi32(texel, 16), byte));
            if (q == 0) {
                R = _mm512_mul_ps(w[0], tr), G = _mm512_mul_ps(w[0], tg), B = _mm512_mul_ps(w[0], tb);
            } else {
                R = _mm512_fmadd_ps(w[q], tr, R), G = _mm512_fmadd_ps(w[q], tg, G), B = _mm512_fmadd_ps(w[q], tb, B);
            }
        }
    };
    __m512 R, G, B;
    bilinear(fine_taps, fine, R, G, B);
    if (blending) {  // f + blend (g - f); the lanes that blend nothing read their fine level again
        __m512 R1, G1, B1;
        bilinear(coarse_taps, coarse, R1, G1, B1);
        R = _mm512_fmadd_ps(blend, _mm512_sub_ps(R1, R), R);
        G = _mm512_fmadd_ps(blend, _mm512_sub_ps(G1, G), G);
        B = _mm512_fmadd_ps(blend, _mm512_sub_ps(B1, B), B);
    }
    _mm512_storeu_ps(r, R), _mm512_storeu_ps(g, G), _mm512_storeu_ps(b, B);
    return true;
}

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

bool TrilinearLanes::sample16(const PacketUv& packet, float* r, float* g, float* b) {
    if (!state_) return false;
    State& st = *state_;
    const std::uint32_t width = st.pyramid.width, height = st.pyramid.height;
    // Below 2^22 texels a side the float tile division below is exact (see cell) and every
    // texel index and level extent is a float.
    constexpr std::uint32_t kMaxSide = 1u << 22;
    if (width >= kMaxSide || height >= kMaxSide) return false;
    const LaneLevels lv = lane_levels(packet.lod, st.pyramid.top, st.levels);
    // The packet's levels: its finest L and at most L + 1 at the fine level (so L + 2 at the
    // coarse one). Nearly always every lane's is lane 0's: then no reduction over the lanes.
    std::int32_t L = _mm_cvtsi128_si32(_mm512_castsi512_si128(lv.l0));
    const bool levels_differ = _mm512_cmpneq_epi32_mask(lv.l0, _mm512_set1_epi32(L)) != 0;
    if (levels_differ) {
        L = _mm512_reduce_min_epi32(lv.l0);
        if (_mm512_reduce_max_epi32(lv.l0) > L + 1) return false;
    }
    const __m512i one_i = _mm512_set1_epi32(1);
    const TileExtent t = st.tile;
    const __m512 du = _mm512_load_ps(packet.du), dv = _mm512_load_ps(packet.dv);
    // One axis at level L: lane 0's continuous texel position less 1/2 (trilinear_taps' tx
    // before its clamp), X = c0 extent 2^-L - 1/2, as an integer origin and a fraction; each
    // lane's position relative to the origin is frac + d extent 2^-L in float. Level L + k's
    // position is (X + 1/2) 2^-k - 1/2 = origin_k + (rel 2^-k + frac_k), with origin_k and
    // frac_k the same split of (origin + 1/2) 2^-k - 1/2 (level_origin, exact).
    struct Axis {
        __m512 rel;           // per lane, at level L
        std::int32_t origin;  // at level L
    };
    // Level L + k's origin and fraction: (o + 1/2) 2^-k - 1/2 = (2o + 1 - 2^k) / 2^(k+1), its
    // floor by an arithmetic shift, its fraction in eighths (made where a level needs them).
    auto level_origin = [](const Axis& a, int k, std::int32_t& origin, __m512& frac) {
        const std::int32_t num = 2 * a.origin + 1 - (1 << k);
        origin = num >> (k + 1);
        frac = _mm512_set1_ps(float(num & ((2 << k) - 1)) / float(2 << k));
    };
    auto axis = [&](double c0, const State::AxisLevel& level, __m512 d, Axis& a) {
        // c0 extent 2^-L as (c0 extent) 2^-L: the scaling by a power of two is exact.
        const double X = c0 * level.scale - 0.5;
        const double o = std::floor(X);
        if (!(std::abs(o) < double(kMaxSide))) return false;  // NaN or far outside
        a.rel = _mm512_fmadd_ps(d, _mm512_set1_ps(float(level.scale)), _mm512_set1_ps(float(X - o)));
        // Two texels inside the painting at level L, so that at levels L, L + 1 and L + 2 no
        // lane reaches trilinear_taps' clamps (to [0, w_l - 1], and of uv to [0, 1]):
        // X_{L+k} = (X + 1/2) 2^-k - 1/2 >= 5/8 - 1/2 > 0 and <= w_{L+k} - 1.
        const double hi = level.limit - o;
        if (_mm512_cmp_ps_mask(a.rel, _mm512_set1_ps(float(2.0 - o)), _CMP_LT_OQ) |
            _mm512_cmp_ps_mask(a.rel, _mm512_set1_ps(float(hi)), _CMP_GT_OQ))
            return false;
        a.origin = std::int32_t(o);
        return true;
    };
    Axis ax, ay;
    if (!axis(packet.u0, st.axis_levels[0][std::size_t(L)], du, ax) ||
        !axis(packet.v0, st.axis_levels[1][std::size_t(L)], dv, ay))
        return false;
    // NaN positions fail neither comparison above: refuse them here.
    if (_mm512_cmp_ps_mask(ax.rel, ay.rel, _CMP_UNORD_Q)) return false;
#if defined(__AVX512VBMI__) && defined(__AVX512BW__)
    // The common packet in fewer steps: every lane's fine level L, and at each level every
    // lane's nearest texel in one tile (trilinear_taps' tile for every lane) and its footprint
    // on one pair of texel rows. Per level, each row's stretch is loaded once and every
    // channel of every corner picked into its own lane by one byte permute. The same taps,
    // texels, products and sums as below.
    if (!levels_differ) {
        // Level L + k's origins, each lane's texel from them (the floor of its position) and
        // its weights.
        struct LevelPosition {
            std::int32_t ox, oy;
            __m512 fx, fy;
            __m512i ix, iy, nx, ny;
        };
        auto level_position = [&](int k) __attribute__((always_inline)) {
            LevelPosition p;
            p.ox = ax.origin, p.oy = ay.origin;
            __m512 x = ax.rel, y = ay.rel;
            if (k) {
                __m512 fx0, fy0;
                level_origin(ax, k, p.ox, fx0), level_origin(ay, k, p.oy, fy0);
                const __m512 half = _mm512_set1_ps(0.5f);
                x = _mm512_fmadd_ps(x, half, fx0), y = _mm512_fmadd_ps(y, half, fy0);
            }
            const __m512 x_fl = _mm512_roundscale_ps(x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
            const __m512 y_fl = _mm512_roundscale_ps(y, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
            p.fx = _mm512_sub_ps(x, x_fl), p.fy = _mm512_sub_ps(y, y_fl);
            p.ix = _mm512_cvttps_epi32(x_fl), p.iy = _mm512_cvttps_epi32(y_fl);
            // Every lane's nearest texel (trilinear_taps' n_up), less the origin.
            const __m512 half = _mm512_set1_ps(0.5f);
            p.nx = _mm512_mask_add_epi32(p.ix, _mm512_cmp_ps_mask(p.fx, half, _CMP_GE_OQ), p.ix, one_i);
            p.ny = _mm512_mask_add_epi32(p.iy, _mm512_cmp_ps_mask(p.fy, half, _CMP_GE_OQ), p.iy, one_i);
            return p;
        };
        // At a level's position p in lane 0's tile: each lane's footprint's first texel in the
        // tile (border included), the stretch of bytes from lo on that the footprints' corners
        // span on their rows, and whether it fits one byte permute: every footprint on the
        // same pair of texel rows, within 128 bytes.
        struct Stretch {
            std::int32_t first_row, lo, span;
            __m512i rel;  // each lane's first texel less lo
            bool fits;
        };
        auto stretch_in = [&](const LevelPosition& p, const State::LastTile& tile) __attribute__((always_inline)) {
            Stretch s;
            const __m512i jx = _mm512_sub_epi32(p.ix, _mm512_set1_epi32(tile.x0 - t.border - p.ox));
            const __m512i jy = _mm512_sub_epi32(p.iy, _mm512_set1_epi32(tile.y0 - t.border - p.oy));
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
        };
        // A level's bilinear blends of 16 lanes from each row's stretch (its two 64-byte
        // halves): every channel of every corner picked into its lane by one byte permute.
        auto blend_rows = [&](const __m512i (&rows)[2][2], const Stretch& s, const LevelPosition& p, __m512& R,
                              __m512& G, __m512& B) __attribute__((always_inline)) {
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
                        const __m512i idx = corner ? _mm512_add_epi32(byte0, _mm512_load_si512(st.corner_bytes[corner])) : byte0;
                        const __m512 texel = _mm512_cvtepi32_ps(_mm512_maskz_permutex2var_epi8(kLowBytes, rows[row][0], idx, rows[row][1]));
                        sum[c] = row == 0 && right == 0 ? _mm512_mul_ps(w[0][0], texel)
                                                        : _mm512_fmadd_ps(w[row][right], texel, sum[c]);
                    }
            R = sum[0], G = sum[1], B = sum[2];
        };
        // Whether the last tile c at level l holds texel (x, y) (its cx = floor(x / P) exactly
        // when x - cx P lies in [0, P)).
        auto holds = [&](const State::LastTile& c, std::int32_t l, std::int32_t x, std::int32_t y) {
            return c.level == l && std::uint32_t(x - c.x0) < std::uint32_t(t.payload) &&
                   std::uint32_t(y - c.y0) < std::uint32_t(t.payload);
        };
        // A level whose lanes' nearest texels (trilinear_taps' tile for each lane) all lie in
        // lane 0's tile.
        auto one_tile = [&](int k, int finder, __m512& R, __m512& G, __m512& B) __attribute__((always_inline)) {
            const LevelPosition p = level_position(k);
            // Lane 0's tile by its nearest texel, as trilinear_taps: the last one's, or the
            // neighbour last taken with it, when either holds that texel.
            const std::int32_t nx = p.ox + _mm_cvtsi128_si32(_mm512_castsi512_si128(p.nx));
            const std::int32_t ny = p.oy + _mm_cvtsi128_si32(_mm512_castsi512_si128(p.ny));
            State::LastTile& tile = st.last_tile[finder];
            if (!holds(tile, L + k, nx, ny)) {
                State::LastTile& other = st.last_tile[finder + 1];
                if (holds(other, L + k, nx, ny)) {
                    std::swap(tile, other);
                } else {
                    const std::uint32_t cx = st.divide_p(std::uint32_t(nx)), cy = st.divide_p(std::uint32_t(ny));
                    tile = {L + k, std::int32_t(cx), std::int32_t(cy), std::int32_t(cx) * t.payload,
                            std::int32_t(cy) * t.payload, st.base(finder, std::uint32_t(L + k), cx, cy)};
                }
            }
            const Stretch s = stretch_in(p, tile);
            // Every lane's nearest texel in the tile's payload (its tile is lane 0's: a lane of
            // another tile would read this one's border where trilinear_taps might fall back).
            const __m512i payload = _mm512_set1_epi32(t.payload);
            if ((_mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.nx, _mm512_set1_epi32(tile.x0 - p.ox)), payload) &
                 _mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.ny, _mm512_set1_epi32(tile.y0 - p.oy)), payload)) != 0xFFFF ||
                !s.fits || !tile.base)
                return false;
            const std::uint8_t* first = tile.base + std::size_t(s.first_row) * std::size_t(t.row_bytes) + std::size_t(s.lo) * 3;
            const auto [m0, m1] = stretch_masks(s.span);
            prefetch_rows_below(first, t.row_bytes);
            __m512i rows[2][2];
            for (int row = 0; row < 2; ++row) {
                const std::uint8_t* q = first + row * t.row_bytes;
                rows[row][0] = _mm512_maskz_loadu_epi8(m0, q), rows[row][1] = _mm512_maskz_loadu_epi8(m1, q + 64);
            }
            blend_rows(rows, s, p, R, G, B);
            return true;
        };
        // A level whose lanes lie in lane 0's tile and its neighbour on the left or right (a
        // packet across a tile's edge; one_tile declined it, leaving lane 0's tile in
        // last_tile[finder]): one_tile's checks for the lanes' two tiles, each row's stretch
        // as the level's bytes from both (State::across_edge). The position and stretch are
        // one_tile's, written again rather than handed over: GCC shares them, and one function
        // for both paths cost the common packets more (bench/RESULTS.md at 177a369).
        auto two_tiles = [&](int k, int finder, __m512& R, __m512& G, __m512& B) __attribute__((always_inline)) {
            const LevelPosition p = level_position(k);
            const State::LastTile& tile = st.last_tile[finder];
            const Stretch s = stretch_in(p, tile);
            const __m512i payload = _mm512_set1_epi32(t.payload);
            const __mmask16 in_tile = _mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.nx, _mm512_set1_epi32(tile.x0 - p.ox)), payload);
            __m512i rows[2][2];
            if (in_tile == 0xFFFF || !tile.base || !s.fits ||
                _mm512_cmplt_epu32_mask(_mm512_sub_epi32(p.ny, _mm512_set1_epi32(tile.y0 - p.oy)), payload) != 0xFFFF ||
                !st.across_edge(L + k, finder, p.nx, tile.x0 - p.ox, in_tile, s.lo, s.span,
                                std::size_t(s.first_row) * std::size_t(t.row_bytes), rows))
                return false;
            blend_rows(rows, s, p, R, G, B);
            return true;
        };
        __m512 R, G, B, R1, G1, B1;
        if ((one_tile(0, 0, R, G, B) || two_tiles(0, 0, R, G, B)) &&
            (!lv.blending || one_tile(1, 2, R1, G1, B1) || two_tiles(1, 2, R1, G1, B1))) {
            if (lv.blending) {
                R = _mm512_fmadd_ps(lv.blend, _mm512_sub_ps(R1, R), R);
                G = _mm512_fmadd_ps(lv.blend, _mm512_sub_ps(G1, G), G);
                B = _mm512_fmadd_ps(lv.blend, _mm512_sub_ps(B1, B), B);
            }
            _mm512_storeu_ps(r, R), _mm512_storeu_ps(g, G), _mm512_storeu_ps(b, B);
            return true;
        }
    }
#endif
    const __m512 inv_p = _mm512_set1_ps(1.0f / float(t.payload));
    // A level's taps from the lanes' levels l (L or L + 1 or L + 2).
    auto taps = [&](__m512i l) {
        const __m512i k = _mm512_sub_epi32(l, _mm512_set1_epi32(L));
        const __mmask16 k1 = _mm512_cmpeq_epi32_mask(k, one_i), k2 = _mm512_cmpeq_epi32_mask(k, _mm512_set1_epi32(2));
        const __m512 minus_k = _mm512_cvtepi32_ps(_mm512_sub_epi32(_mm512_setzero_si512(), k));
        auto one_axis = [&](const Axis& a, __m512& f, __m512i& cell, __m512i& in_tile) {
            __m512 x;
            __m512i origin;
            if (!(k1 | k2)) {  // every lane at level L (nearly always)
                x = a.rel, origin = _mm512_set1_epi32(a.origin);
            } else {
                std::int32_t o1, o2;
                __m512 f1, f2;
                level_origin(a, 1, o1, f1), level_origin(a, 2, o2, f2);
                const __m512 frac = _mm512_mask_blend_ps(k2, _mm512_maskz_mov_ps(k1, f1), f2);
                origin = _mm512_mask_blend_epi32(k1, _mm512_set1_epi32(a.origin), _mm512_set1_epi32(o1));
                origin = _mm512_mask_blend_epi32(k2, origin, _mm512_set1_epi32(o2));
                x = _mm512_add_ps(_mm512_scalef_ps(a.rel, minus_k), frac);
            }
            const __m512 fl = _mm512_roundscale_ps(x, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
            f = _mm512_sub_ps(x, fl);
            const __m512i i = _mm512_add_epi32(origin, _mm512_cvttps_epi32(fl));
            const __m512i n_up = _mm512_mask_add_epi32(i, _mm512_cmp_ps_mask(f, _mm512_set1_ps(0.5f), _CMP_GE_OQ), i, one_i);
            // floor(n_up / P) as Divider::by_double in float: (n + 1/2) fl(1/P) is within
            // 2^-23 (n + 1/2) / P of (n + 1/2) / P, below 1 / (2P) for n < 2^22.
            cell = _mm512_cvttps_epi32(_mm512_mul_ps(_mm512_add_ps(_mm512_cvtepi32_ps(n_up), _mm512_set1_ps(0.5f)), inv_p));
            const __m512i j = _mm512_add_epi32(_mm512_sub_epi32(i, _mm512_mullo_epi32(cell, _mm512_set1_epi32(t.payload))),
                                               _mm512_set1_epi32(t.border));
            in_tile = _mm512_min_epi32(_mm512_max_epi32(j, _mm512_setzero_si512()), _mm512_set1_epi32(t.tile - 2));
        };
        LevelTaps lt;
        lt.level = l;
        __m512i jx, jy;
        one_axis(ax, lt.fx, lt.cx, jx);
        one_axis(ay, lt.fy, lt.cy, jy);
        lt.row = jy;
        lt.offset = _mm512_add_epi32(_mm512_mullo_epi32(jy, _mm512_set1_epi32(t.row_bytes)),
                                     _mm512_mullo_epi32(jx, _mm512_set1_epi32(3)));
        return lt;
    };
    const LevelTaps fine_taps = taps(lv.l0);
    LevelTaps coarse_taps = fine_taps;
    if (lv.blending) coarse_taps = taps(_mm512_mask_add_epi32(lv.l0, lv.blending, lv.l0, one_i));
    return st.sample(fine_taps, coarse_taps, lv, r, g, b);
}
#pragma GCC diagnostic pop
#else
bool TrilinearLanes::sample16(const PacketUv&, float*, float*, float*) { return false; }
#endif

void sample_trilinear_reference(const VirtualTexture& vt, const SampleRequest& r) {
    check_request(vt, r);
    const auto lock = vt.read_lock();
    sample_trilinear_serial(vt, r, 0, r.count);
}

}  // namespace gigascroll
