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
#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "common/vec3.h"
#include "views/camera.h"

namespace gigascroll {
namespace display {

constexpr std::uint64_t kUnclaimed = ~std::uint64_t(0);
// Rows per chunk of the right eye's pass with reuse: each chunk's first and last claim rows
// are reset after the pass (2 rows in 16), the others by the chunk itself.
constexpr std::size_t kReleaseChunkRows = 16;

// The left eye's hits projected into the right eye, 16 lanes (one packet) at a time, and
// their claims on the right pixels. The projection is Camera::project (seed 001 eqs. 3-5)
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
#if defined(__AVX512F__)
        // All 16 lanes in one vector: the same operations in the same order as the loop below
        // (GCC 12's false -Wmaybe-uninitialized in its AVX-512 intrinsics, bug 105593, muted).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
        {
            const __m512 ex_ = _mm512_set1_ps(eye.x), ey_ = _mm512_set1_ps(eye.y), ez_ = _mm512_set1_ps(eye.z);
            const __m512 zero = _mm512_setzero_ps();
            auto dot3 = [](__m512 ax, __m512 ay, __m512 az, __m512 bx, __m512 by, __m512 bz) {
                return _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(ax, bx), _mm512_mul_ps(ay, by)),
                                     _mm512_mul_ps(az, bz));
            };
            const __m512 x = _mm512_load_ps(px), y = _mm512_load_ps(py), z = _mm512_load_ps(pz);
            const __m512 facing = dot3(_mm512_sub_ps(ex_, x), _mm512_sub_ps(ey_, y), _mm512_sub_ps(ez_, z),
                                       _mm512_load_ps(nx), _mm512_load_ps(ny), _mm512_load_ps(nz));
            const __m512 ex = _mm512_sub_ps(x, ex_), ey = _mm512_sub_ps(y, ey_), ez = _mm512_sub_ps(z, ez_);
            const __m512 dx = dot3(ex, ey, ez, _mm512_set1_ps(rgt.x), _mm512_set1_ps(rgt.y), _mm512_set1_ps(rgt.z));
            const __m512 dy = dot3(ex, ey, ez, _mm512_set1_ps(up.x), _mm512_set1_ps(up.y), _mm512_set1_ps(up.z));
            const __m512 dz = dot3(ex, ey, ez, _mm512_set1_ps(fwd.x), _mm512_set1_ps(fwd.y), _mm512_set1_ps(fwd.z));
            const __m512 inv_z = _mm512_div_ps(_mm512_set1_ps(1.0f), dz);
            const __m512 fx = _mm512_roundscale_ps(
                _mm512_add_ps(_mm512_set1_ps(0.5f * fw), _mm512_mul_ps(_mm512_mul_ps(dx, inv_z), _mm512_set1_ps(sx))),
                _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
            const __m512 fy = _mm512_roundscale_ps(
                _mm512_sub_ps(_mm512_set1_ps(0.5f * fh), _mm512_mul_ps(_mm512_mul_ps(dy, inv_z), _mm512_set1_ps(sy))),
                _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC);
            const __m512i hits = _mm512_load_si512(hit);
            __mmask16 ok = _mm512_test_epi32_mask(hits, hits) & _mm512_cmp_ps_mask(facing, zero, _CMP_NLE_UQ);
            ok &= _mm512_cmp_ps_mask(dz, zero, _CMP_GT_OQ);
            ok &= _mm512_cmp_ps_mask(fx, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(fx, _mm512_set1_ps(fw), _CMP_LT_OQ);
            ok &= _mm512_cmp_ps_mask(fy, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(fy, _mm512_set1_ps(fh), _CMP_LT_OQ);
            // Where ok, fx and fy are integers in [0, 2^31): the conversion is exact.
            const __m512i t = _mm512_add_epi32(_mm512_mullo_epi32(_mm512_cvttps_epi32(fy), _mm512_set1_epi32(int(rw))),
                                               _mm512_cvttps_epi32(fx));
            _mm512_store_si512(target, _mm512_mask_blend_epi32(ok, _mm512_set1_epi32(int(kNoTarget)), t));
            _mm512_store_ps(depth, dz);
        }
#pragma GCC diagnostic pop
#elif defined(__AVX2__)
        // 8 lanes at once: the same operations in the same order as the loop below (GCC 12
        // keeps that loop scalar: "control flow in loop").
        const __m256 ex_ = _mm256_set1_ps(eye.x), ey_ = _mm256_set1_ps(eye.y),
                     ez_ = _mm256_set1_ps(eye.z), zero = _mm256_setzero_ps();
        const __m256 half_w = _mm256_set1_ps(0.5f * fw), half_h = _mm256_set1_ps(0.5f * fh);
        const __m256 vfw = _mm256_set1_ps(fw), vfh = _mm256_set1_ps(fh);
        const __m256 vsx = _mm256_set1_ps(sx), vsy = _mm256_set1_ps(sy);
        const __m256i vrw = _mm256_set1_epi32(int(rw));
        auto dot3 = [](__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz) {
            return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(ax, bx), _mm256_mul_ps(ay, by)),
                                 _mm256_mul_ps(az, bz));
        };
        for (int k = 0; k < 16; k += 8) {
            const __m256 x = _mm256_load_ps(px + k), y = _mm256_load_ps(py + k),
                         z = _mm256_load_ps(pz + k);
            const __m256 facing =
                dot3(_mm256_sub_ps(ex_, x), _mm256_sub_ps(ey_, y), _mm256_sub_ps(ez_, z),
                     _mm256_load_ps(nx + k), _mm256_load_ps(ny + k), _mm256_load_ps(nz + k));
            const __m256 ex = _mm256_sub_ps(x, ex_), ey = _mm256_sub_ps(y, ey_),
                         ez = _mm256_sub_ps(z, ez_);
            const __m256 dx = dot3(ex, ey, ez, _mm256_set1_ps(rgt.x), _mm256_set1_ps(rgt.y),
                                   _mm256_set1_ps(rgt.z));
            const __m256 dy = dot3(ex, ey, ez, _mm256_set1_ps(up.x), _mm256_set1_ps(up.y),
                                   _mm256_set1_ps(up.z));
            const __m256 dz = dot3(ex, ey, ez, _mm256_set1_ps(fwd.x), _mm256_set1_ps(fwd.y),
                                   _mm256_set1_ps(fwd.z));
            const __m256 inv_z = _mm256_div_ps(_mm256_set1_ps(1.0f), dz);
            const __m256 fx = _mm256_floor_ps(
                _mm256_add_ps(half_w, _mm256_mul_ps(_mm256_mul_ps(dx, inv_z), vsx)));
            const __m256 fy = _mm256_floor_ps(
                _mm256_sub_ps(half_h, _mm256_mul_ps(_mm256_mul_ps(dy, inv_z), vsy)));
            __m256 ok = _mm256_and_ps(
                _mm256_castsi256_ps(_mm256_load_si256(reinterpret_cast<const __m256i*>(hit + k))),
                _mm256_cmp_ps(facing, zero, _CMP_NLE_UQ));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(dz, zero, _CMP_GT_OQ));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(fx, zero, _CMP_GE_OQ));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(fx, vfw, _CMP_LT_OQ));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(fy, zero, _CMP_GE_OQ));
            ok = _mm256_and_ps(ok, _mm256_cmp_ps(fy, vfh, _CMP_LT_OQ));
            // Where ok, fx and fy are integers in [0, 2^31): the conversion is exact.
            const __m256i t = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(fy), vrw),
                                               _mm256_cvttps_epi32(fx));
            const __m256i tk = _mm256_blendv_epi8(_mm256_set1_epi32(int(kNoTarget)), t,
                                                  _mm256_castps_si256(ok));
            _mm256_store_si256(reinterpret_cast<__m256i*>(target + k), tk);
            _mm256_store_ps(depth + k, dz);
        }
#else
        for (int k = 0; k < 16; ++k) {
            const Vec3f p{px[k], py[k], pz[k]}, to_eye = eye - p;
            const float facing = dot(to_eye, Vec3f{nx[k], ny[k], nz[k]});  // <= 0: the other side
            const Vec3f d = p - eye;
            const float dx = dot(d, rgt), dy = dot(d, up), dz = dot(d, fwd);
            const float inv_z = 1.0f / dz;
            const float fx = std::floor(0.5f * fw + dx * inv_z * sx);
            const float fy = std::floor(0.5f * fh - dy * inv_z * sy);
            const bool ok = hit[k] && !(facing <= 0.0f) && dz > 0.0f && fx >= 0.0f && fx < fw &&
                            fy >= 0.0f && fy < fh;
            target[k] = ok ? std::uint32_t(fy) * rw + std::uint32_t(fx) : kNoTarget;
            depth[k] = dz;  // dot(p - eye, fwd): the depth along the right eye's axis
        }
#endif
        for (std::uint32_t k = 0; k < 16; ++k)
            if (target[k] != kNoTarget) __builtin_prefetch(claims + target[k], 1);
    }

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

}  // namespace display
}  // namespace gigascroll
