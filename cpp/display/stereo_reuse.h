// The "reuse" step of the display pass (display/display_pass.h's header comment): the left
// eye's hits claim the right pixels they project to, the claims on a depth edge are released,
// and the right eye takes the kept claims' hits instead of tracing them.
#pragma once
#include <algorithm>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "common/lanes.h"
#include "common/vec3.h"
#include "views/camera.h"

namespace gigascroll {
namespace display {

constexpr std::uint64_t kUnclaimed = ~std::uint64_t(0);
// Rows per chunk of the right eye's pass with reuse: each chunk's first and last claim rows
// are reset after the pass (2 rows in 16), the others by the chunk itself.
constexpr std::size_t kReleaseChunkRows = 16;

// The left eye's hits projected into the right eye, 16 lanes (one packet) at a time, and
// their claims on the right pixels. The projection is Camera::project (VR-photon-mapping eqs. 3-5)
// with its constants hoisted and one division per point: pixel = floor((x / (z tan_x) + 1)
// w / 2), floor((1 - y / (z tan_y)) h / 2); a hit claims that pixel if it faces the right eye
// and projects into its image. The nearest claim per right pixel wins: depth along the right
// eye's axis in the high word, so the smaller 64-bit value is the nearer claim (positive
// floats order as their bits), the left pixel in the low word, by compare-and-swap.
struct ClaimProjection {
    Vec3f eye, fwd, rgt, up;
    float fw, fh, sx, sy;
    std::uint32_t rw;
    std::uint64_t* claims;
    static constexpr std::uint32_t kNoTarget = ~0u;

    ClaimProjection(const Camera& right, std::uint64_t* claims_)
        : eye(right.position), fwd(right.forward), rgt(right.right), up(right.up),
          fw(float(right.width)), fh(float(right.height)),
          sx(0.5f * fw / float(right.tan_half_x)), sy(0.5f * fh / float(right.tan_half_y)),
          rw(right.width), claims(claims_) {}

    // Lanes with hit[k] != 0 (hit points p, eye-facing normals n): their right pixel in
    // target (kNoTarget: no claim) and depth, and the claims' cache lines fetched for writing
    // (claim() comes later, when they have arrived: a locked compare-and-swap waits for its
    // line).
    void project16(const float* px, const float* py, const float* pz, const float* nx,
                   const float* ny, const float* nz, const int* hit, std::uint32_t* target,
                   float* depth) const {
        project<kWidest>(px, py, pz, nx, ny, nz, hit, target, depth);
        for (std::uint32_t k = 0; k < 16; ++k)
            if (target[k] != kNoTarget) __builtin_prefetch(claims + target[k], 1);
    }

    // The projection of 16 lanes, W at a time (common/lanes.h: the same floats at every
    // width). A facing test that is NaN does not refuse the claim (!(facing <= 0)).
// GCC 12's false -Wmaybe-uninitialized in its AVX-512 intrinsics (bug 105593), muted.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    template <int W>
    void project(const float* px, const float* py, const float* pz, const float* nx, const float* ny,
                 const float* nz, const int* hit, std::uint32_t* target, float* depth) const {
        using L = Lanes<W>;
        using F = typename L::F;
        using I = typename L::I;
        const F ex_(eye.x), ey_(eye.y), ez_(eye.z), zero(0.0f);
        auto dot3 = [](F ax, F ay, F az, F bx, F by, F bz) { return ax * bx + ay * by + az * bz; };
        for (int k = 0; k < 16; k += W) {
            const F x = F::load(px + k), y = F::load(py + k), z = F::load(pz + k);
            const F facing = dot3(ex_ - x, ey_ - y, ez_ - z, F::load(nx + k), F::load(ny + k), F::load(nz + k));
            const F ex = x - ex_, ey = y - ey_, ez = z - ez_;
            const F dx = dot3(ex, ey, ez, F(rgt.x), F(rgt.y), F(rgt.z));
            const F dy = dot3(ex, ey, ez, F(up.x), F(up.y), F(up.z));
            const F dz = dot3(ex, ey, ez, F(fwd.x), F(fwd.y), F(fwd.z));  // depth along the right eye's axis
            const F inv_z = F(1.0f) / dz;
            const F fx = floor(F(0.5f * fw) + dx * inv_z * F(sx));
            const F fy = floor(F(0.5f * fh) - dy * inv_z * F(sy));
            const auto ok = nonzero(I::load(hit + k)) & !(facing <= zero) & (dz > zero) & (fx >= zero) &
                            (fx < F(fw)) & (fy >= zero) & (fy < F(fh));
            // Where ok, fx and fy are integers in [0, 2^31): the conversion is exact.
            L::select(ok, to_int(fy) * I(std::int32_t(rw)) + to_int(fx), I(std::int32_t(kNoTarget)))
                .store(target + k);
            dz.store(depth + k);
        }
    }
#pragma GCC diagnostic pop

    // The right pixels a thread may claim without a compare-and-swap. With rows_aligned (the
    // right eye is the left one moved along their common right axis, so a point projects
    // into the same row of both, to float rounding) a claim is only made within one row of
    // its left pixel's row (the rare other one is dropped: the right eye traces that pixel).
    // Then a row strictly inside the chunk of left rows [rb, re) that this thread renders is
    // claimed by this chunk's pixels alone, and its claims are a plain minimum (a locked
    // compare-and-swap per left pixel drained the store buffer: a twelfth of the left eye);
    // claims on the chunk's first and last rows and the rows beside them, which the
    // neighbouring chunks' threads claim too, stay compare-and-swaps. The minimum does not
    // depend on the order: the same claims win either way.
    struct ClaimRows {
        std::uint32_t plain_begin = 0, plain_end = 0;  // pixel indices of the chunk's inner rows
        std::uint32_t near_begin = 0, near_end = ~0u;  // rows row - 1 .. row + 1 (aligned)
    };
    ClaimRows claim_rows(bool rows_aligned, std::size_t row, std::size_t rb, std::size_t re) const {
        ClaimRows r;
        if (!rows_aligned) return r;  // every claim a compare-and-swap, none dropped
        if (re >= rb + 3) r.plain_begin = std::uint32_t((rb + 1) * rw), r.plain_end = std::uint32_t((re - 1) * rw);
        r.near_begin = std::uint32_t((row > 0 ? row - 1 : 0) * rw);
        r.near_end = std::uint32_t(std::min<std::size_t>(row + 2, std::size_t(fh)) * rw);
        return r;
    }

    // The projected lanes' claims; lane k is the left pixel first + k.
    void claim16(const std::uint32_t* target, const float* depth, std::uint32_t first,
                 const ClaimRows& rows) const {
        for (std::uint32_t k = 0; k < 16; ++k) {
            const std::uint32_t t = target[k];
            if (t == kNoTarget || t < rows.near_begin || t >= rows.near_end) continue;
            const std::uint64_t claim =
                (std::uint64_t(std::bit_cast<std::uint32_t>(depth[k])) << 32) | std::uint64_t(first + k);
            std::atomic_ref<std::uint64_t> slot(claims[t]);
            std::uint64_t seen = slot.load(std::memory_order_relaxed);
            if (t >= rows.plain_begin && t < rows.plain_end) {  // no other writer
                if (claim < seen) slot.store(claim, std::memory_order_relaxed);
                continue;
            }
            while (claim < seen && !slot.compare_exchange_weak(seen, claim, std::memory_order_relaxed)) {
            }
        }
    }
};

// Whether a point projects into the same row of both eyes (to float rounding): the same
// orientation and intrinsics, and the eyes apart along their right axis only.
bool rows_align(const Camera& left, const Camera& right);

// Per pixel of one row of claims, the nearest claimed depth among it and its two row
// neighbours (the separable 3 x 3 minimum's first pass; unclaimed: infinitely far).
void claimed_row_min(const std::uint64_t* __restrict claims, std::size_t w, float* __restrict depths,
                     float* __restrict row_min);

// The edge release of one row of claims (see DisplayPass::reuse): a claim is kept unless its
// depth exceeds the 3 x 3 minimum of claimed depths (the row minima of the rows above, at
// and below) x ratio; source gets the kept claim's left pixel, else -1. Returns the count
// kept; with reset, the row's claims are left unclaimed for the next frame.
std::uint64_t release_claims(std::uint64_t* __restrict claims, const float* up, const float* mid,
                             const float* down, std::size_t w, float ratio,
                             std::int32_t* __restrict source, bool reset);

// W claims from claims[0] in lanes: their depths (high words), left pixels (low words) and
// the unclaimed lanes, in pixel order. The words' deinterleave is a permute (two at 16
// lanes, shuffles at 8), each width's own; W = 1 is the plain split.
template <int W>
struct ClaimLanes {
    typename Lanes<W>::F depth;
    typename Lanes<W>::I index;
    typename Lanes<W>::M unclaimed;
};
inline ClaimLanes<1> load_claims(const std::uint64_t* claims, std::integral_constant<int, 1>) {
    const std::uint64_t c = claims[0];
    return {Lanes<1>::F(std::bit_cast<float>(std::uint32_t(c >> 32))), Lanes<1>::I(std::int32_t(c & 0xffffffffu)),
            {c == kUnclaimed}};
}
#if defined(__AVX2__)
inline ClaimLanes<8> load_claims(const std::uint64_t* claims, std::integral_constant<int, 8>) {
    const __m256i c0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(claims));
    const __m256i c1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(claims + 4));
    // Per 128-bit lane the odd (even) words of c0 and c1, then the 64-bit quarters reordered.
    auto words = [](__m256i a, __m256i b, auto odd) {
        constexpr int kPick = decltype(odd)::value ? _MM_SHUFFLE(3, 1, 3, 1) : _MM_SHUFFLE(2, 0, 2, 0);
        return _mm256_castpd_si256(_mm256_permute4x64_pd(
            _mm256_castps_pd(_mm256_shuffle_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b), kPick)),
            _MM_SHUFFLE(3, 1, 2, 0)));
    };
    const __m256i ones = _mm256_set1_epi64x(-1);
    const __m256i unclaimed = words(_mm256_cmpeq_epi64(c0, ones), _mm256_cmpeq_epi64(c1, ones), std::true_type{});
    return {Lanes<8>::F(_mm256_castsi256_ps(words(c0, c1, std::true_type{}))),
            Lanes<8>::I(words(c0, c1, std::false_type{})), {_mm256_castsi256_ps(unclaimed)}};
}
#endif
#if defined(__AVX512F__)
inline ClaimLanes<16> load_claims(const std::uint64_t* claims, std::integral_constant<int, 16>) {
    const __m512i c0 = _mm512_loadu_si512(claims), c1 = _mm512_loadu_si512(claims + 8);
    const __m512i odd = _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31);
    const __m512i even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
    const __m512i ones = _mm512_set1_epi64(-1);
    const __mmask16 unclaimed = __mmask16(unsigned(_mm512_cmpeq_epi64_mask(c0, ones)) |
                                          unsigned(_mm512_cmpeq_epi64_mask(c1, ones)) << 8);
    return {Lanes<16>::F(_mm512_castsi512_ps(_mm512_permutex2var_epi32(c0, odd, c1))),
            Lanes<16>::I(_mm512_permutex2var_epi32(c0, even, c1)), {unclaimed}};
}
#endif

// release_claims' test of whole groups of W claims from x = 0 (the count kept added to
// kept); returns the first x not taken (w less its remainder mod W). std::min(a, b) is
// b < a ? b : a, the lanes' min(b, a).
template <int W>
std::size_t release_claim_lanes(const std::uint64_t* __restrict claims, const float* up, const float* mid,
                                const float* down, std::size_t w, float ratio, std::int32_t* __restrict source,
                                std::uint64_t& kept) {
    using L = Lanes<W>;
    using F = typename L::F;
    std::size_t x = 0;
    for (; x + W <= w; x += W) {
        const F nearest = min(F::load(down + x), min(F::load(mid + x), F::load(up + x)));
        const ClaimLanes<W> c = load_claims(claims + x, std::integral_constant<int, W>{});
        const auto drop = (c.depth > nearest * F(ratio)) | c.unclaimed;
        L::select(drop, typename L::I(-1), c.index).store(source + x);
        kept += std::uint64_t(W - std::popcount(drop.bits()));
    }
    return x;
}

}  // namespace display
}  // namespace gigascroll
