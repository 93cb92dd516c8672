#include "sampling/stereo_display.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <limits>
#include <mutex>
#include <optional>
#include <string>
#if defined(__AVX__)
#include <immintrin.h>
#elif defined(__SSE__)
#include <xmmintrin.h>
#endif

#include "common/timing.h"
#include "common/error.h"
#include "common/parallel.h"
#include "sampling/sampler.h"
#include "sampling/srgb_curve.h"
#include "views/feedback.h"

namespace gigascroll {

namespace {
constexpr unsigned kNoHit = RTC_INVALID_GEOMETRY_ID;
constexpr std::uint64_t kUnclaimed = ~std::uint64_t(0);

// Casts the primary rays of rows [row_begin, row_end) in 16-ray packets along each row; a
// pixel with reused[i] >= 0 (the right eye's pixels that reuse a left hit) is left out of its
// packet, and a packet left empty is not cast. A row's last packet holds n < 16 pixels when
// the width is not a multiple of 16; with whole_tail (and no reused pixels) its other lanes
// cast its last pixel's ray again, so that the packet can be taken whole. on_row_start(row)
// runs before each row's packets, on_packet(row, i0, n, valid, packet) sees each packet after
// Embree filled it, on_row(row) each row after its last packet.
template <typename OnRowStart, typename OnPacket, typename OnRow>
void cast_rows(RTCScene scene, const Camera& eye, std::size_t row_begin, std::size_t row_end,
               const std::int32_t* reused, bool whole_tail, OnRowStart&& on_row_start,
               OnPacket&& on_packet, OnRow&& on_row) {
    const std::uint32_t w = eye.width;
    const std::size_t padded = (std::size_t(w) + 15) / 16 * 16;
    std::vector<float> dir_x(padded), dir_y(padded), dir_z(padded);
    std::vector<double> column_sx(padded);
    for (std::uint32_t i = 0; i < w; ++i) column_sx[i] = eye.screen_x(i + 0.5);
    std::fill(column_sx.begin() + w, column_sx.end(), column_sx[w - 1]);
    RTCRayHit16 packet;
    for (std::uint32_t k = 0; k < 16; ++k) {
        packet.ray.org_x[k] = float(eye.position.x), packet.ray.org_y[k] = float(eye.position.y);
        packet.ray.org_z[k] = float(eye.position.z);
        packet.ray.tnear[k] = 0.f, packet.ray.time[k] = 0.f, packet.ray.mask[k] = ~0u;
        packet.ray.id[k] = k, packet.ray.flags[k] = 0;
        packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    // The ray directions of columns [begin, end) of a row (one loop the compiler vectorises).
    auto directions = [&](const Vec3d& row_dir, std::size_t begin, std::size_t end) {
        for (std::size_t i = begin; i < end; ++i) {
            const double c = column_sx[i];
            dir_x[i] = float(row_dir.x + c * eye.right.x);
            dir_y[i] = float(row_dir.y + c * eye.right.y);
            dir_z[i] = float(row_dir.z + c * eye.right.z);
        }
    };
    for (std::size_t row = row_begin; row < row_end; ++row) {
        on_row_start(row);
        const Vec3d row_dir = eye.forward + eye.screen_y(row + 0.5) * eye.up;
        const std::int32_t* row_reused = reused ? reused + row * w : nullptr;
        if (!row_reused) directions(row_dir, 0, padded);
        for (std::uint32_t i0 = 0; i0 < w; i0 += 16) {
            const std::uint32_t n = std::min<std::uint32_t>(16, w - i0);
            alignas(64) int valid[16];
            if (row_reused) {
                int any = 0;
                for (std::uint32_t k = 0; k < 16; ++k) {
                    valid[k] = k < n && row_reused[i0 + std::min(k, n - 1)] < 0 ? -1 : 0;
                    any |= valid[k];
                }
                if (!any) continue;
                directions(row_dir, i0, i0 + 16);  // only for the packets that are cast
            } else {  // the lanes below n, all 16 with whole_tail
#if defined(__AVX512F__)
                // One store (GCC kept the loop below scalar: 52 instructions a packet).
                const std::uint32_t lanes = n == 16 || whole_tail ? 0xFFFFu : (1u << n) - 1;
                _mm512_store_si512(valid, _mm512_maskz_set1_epi32(__mmask16(lanes), -1));
#else
                for (std::uint32_t k = 0; k < 16; ++k) valid[k] = k < n || whole_tail ? -1 : 0;
#endif
            }
            for (std::uint32_t k = 0; k < 16; ++k) {
                packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
                packet.hit.geomID[k] = kNoHit;
            }
            std::memcpy(packet.ray.dir_x, dir_x.data() + i0, sizeof packet.ray.dir_x);
            std::memcpy(packet.ray.dir_y, dir_y.data() + i0, sizeof packet.ray.dir_y);
            std::memcpy(packet.ray.dir_z, dir_z.data() + i0, sizeof packet.ray.dir_z);
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            rtcIntersect16(valid, scene, &context, &packet);
            on_packet(row, i0, n, valid, packet);
        }
        on_row(row);
    }
}

// A painting's plane as one eye sees it, so that a pixel's painting coordinates and level of
// detail are a few multiply-adds on its ray direction D (unnormalised, D . forward = 1):
// t = h / (D . n), uv = ((eye - origin) . axis + t D . axis) / size, and the footprint of
// feedback.h's texel_footprint, dP/dx = t (dD/dx - (dD/dx . n) / (D . n) D), expanded on the
// axes. The same arithmetic as texel_footprint in another order. uv in double (a 12 m scroll
// of 150k texels needs more than float), the footprint in float from t, 1 / (D . n) and
// D . axis rounded to float (the level is stored as a float, and a SIMD instruction takes
// twice as many float lanes as double ones): the level is texel_footprint's to about 1e-6.
struct PlaneMap {
    Vec3d n, u_axis, v_axis;
    double h = 0, cu = 0, cv = 0, inv_width = 0, inv_height = 0;
    double xn = 0, xu = 0, xv = 0, yn = 0, yu = 0, yv = 0;  // ddx, ddy . (n, u, v)
    double su = 0, sv = 0;                                  // texels per metre along u, v
    float fxn = 0, fxu = 0, fxv = 0, fyn = 0, fyu = 0, fyv = 0, fsu = 0, fsv = 0;  // as float

    // A row's directions D(x) = row + screen_x(x) right on the plane's normal and axes:
    // D . n = rn + screen_x qn and the same for u and v, a multiply-add per pixel each.
    struct Row {
        double rn = 0, ru = 0, rv = 0, qn = 0, qu = 0, qv = 0;
    };

    PlaneMap(const PaintingPlacement& pp, const Camera& eye)
        : n(pp.normal()), u_axis(pp.u_axis), v_axis(pp.v_axis) {
        h = dot(pp.origin - eye.position, n);
        cu = dot(eye.position - pp.origin, u_axis), cv = dot(eye.position - pp.origin, v_axis);
        inv_width = 1.0 / pp.width_m, inv_height = 1.0 / pp.height_m;
        const Vec3d dx = eye.ddx(), dy = eye.ddy();
        xn = dot(dx, n), xu = dot(dx, u_axis), xv = dot(dx, v_axis);
        yn = dot(dy, n), yu = dot(dy, u_axis), yv = dot(dy, v_axis);
        su = pp.tiles.width() / pp.width_m, sv = pp.tiles.height() / pp.height_m;
        fxn = float(xn), fxu = float(xu), fxv = float(xv), fyn = float(yn), fyu = float(yu);
        fyv = float(yv), fsu = float(su), fsv = float(sv);
    }

    Row row(const Vec3d& row_direction, const Vec3d& right) const {
        return {dot(row_direction, n), dot(row_direction, u_axis), dot(row_direction, v_axis),
                dot(right, n), dot(right, u_axis), dot(right, v_axis)};
    }

    // uv clamped to [0, 1] and lambda = log2(footprint in texels) of count pixels of a row at
    // screen x sx[k]: a loop the compiler vectorises (the painting pixels in SIMD lanes), with
    // log2 by fast_log2f and its rare non-normal footprints patched after the loop. kUv =
    // false: the level alone (the same operations: the same bits as with uv).
    template <bool kUv>
    __attribute__((always_inline)) void map_columns(const Row& r, std::size_t count,
                                                    const double* __restrict sx, double* __restrict u,
                                                    double* __restrict v, float* __restrict lod) const {
        map<kUv>(count, u, v, lod, [&](std::size_t k, double& dn, double& du, double& dv) {
            const double s = sx[k];
            dn = r.rn + s * r.qn, du = r.ru + s * r.qu, dv = r.rv + s * r.qv;
        });
    }

    // The same for rays of any directions D (three arrays).
    __attribute__((always_inline)) void map_lanes(std::size_t count, const double* __restrict Dx,
                                                  const double* __restrict Dy,
                                                  const double* __restrict Dz, double* __restrict u,
                                                  double* __restrict v, float* __restrict lod) const {
        map<true>(count, u, v, lod, [&](std::size_t k, double& dn, double& du, double& dv) {
            dn = Dx[k] * n.x + Dy[k] * n.y + Dz[k] * n.z;
            du = Dx[k] * u_axis.x + Dy[k] * u_axis.y + Dz[k] * u_axis.z;
            dv = Dx[k] * v_axis.x + Dy[k] * v_axis.y + Dz[k] * v_axis.z;
        });
    }

#if defined(__AVX512F__)
// GCC 12's false -Wmaybe-uninitialized in its AVX-512 intrinsics (bug 105593), muted.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
    // A packet of 16 columns from screen x s0 (ds[k]: column k's screen x less s0) as
    // TrilinearLanes takes it: lane 0's uv in double, not clamped (the sampler declines a
    // packet that reaches the painting's edge), the lanes' offsets from it in float, and each
    // lane's level plus bias (sampled_lod). The offset of column s from s0 is
    // du = (s - s0) h (qu rn - ru qn) / (width D.n(s) D.n(s0)) (the same for v): the
    // difference of two uv's without their cancellation, to float's relative precision. The
    // level is footprint2's of t, 1 / (D . n), D . u and D . v in float, as map_columns'.
    // False (out half written) where a footprint is not a normal float: the caller then
    // takes map_columns, which patches it in double.
    bool map_packet(const Row& r, double s0, const float* ds, float bias, PacketUv& out) const {
        const double dn0 = r.rn + s0 * r.qn, du0 = r.ru + s0 * r.qu, dv0 = r.rv + s0 * r.qv;
        const double kk0 = 1.0 / dn0, t0 = h * kk0;
        out.u0 = (cu + t0 * du0) * inv_width, out.v0 = (cv + t0 * dv0) * inv_height;
        const __m512 S = _mm512_loadu_ps(ds);
        const __m512 dn = _mm512_fmadd_ps(S, _mm512_set1_ps(float(r.qn)), _mm512_set1_ps(float(dn0)));
        const __m512 kk = _mm512_div_ps(_mm512_set1_ps(1.0f), dn);
        const __m512 S_kk = _mm512_mul_ps(S, kk);
        _mm512_store_ps(out.du, _mm512_mul_ps(S_kk, _mm512_set1_ps(float(h * inv_width * (r.qu * r.rn - r.ru * r.qn) * kk0))));
        _mm512_store_ps(out.dv, _mm512_mul_ps(S_kk, _mm512_set1_ps(float(h * inv_height * (r.qv * r.rn - r.rv * r.qn) * kk0))));
        // footprint2 in lanes.
        const __m512 t = _mm512_mul_ps(_mm512_set1_ps(float(h)), kk);
        const __m512 Du = _mm512_fmadd_ps(S, _mm512_set1_ps(float(r.qu)), _mm512_set1_ps(float(du0)));
        const __m512 Dv = _mm512_fmadd_ps(S, _mm512_set1_ps(float(r.qv)), _mm512_set1_ps(float(dv0)));
        const __m512 kDu = _mm512_mul_ps(kk, Du), kDv = _mm512_mul_ps(kk, Dv);
        const __m512 tu = _mm512_mul_ps(t, _mm512_set1_ps(fsu)), tv = _mm512_mul_ps(t, _mm512_set1_ps(fsv));
        auto term = [](__m512 scale, float a, float b, __m512 kd) {  // scale (a - b kd)
            return _mm512_mul_ps(scale, _mm512_fnmadd_ps(_mm512_set1_ps(b), kd, _mm512_set1_ps(a)));
        };
        const __m512 ax = term(tu, fxu, fxn, kDu), bx = term(tv, fxv, fxn, kDv);
        const __m512 ay = term(tu, fyu, fyn, kDu), by = term(tv, fyv, fyn, kDv);
        const __m512 fp2 = _mm512_max_ps(_mm512_fmadd_ps(ax, ax, _mm512_mul_ps(bx, bx)),
                                         _mm512_fmadd_ps(ay, ay, _mm512_mul_ps(by, by)));
        // fast_log2f in lanes; zero, subnormal, infinite, NaN or negative: refused.
        constexpr int kNotNormal = 0x01 | 0x02 | 0x04 | 0x08 | 0x10 | 0x20 | 0x40 | 0x80;
        if (_mm512_fpclass_ps_mask(fp2, kNotNormal)) return false;
        const __m512i bits = _mm512_castps_si512(fp2);
        const __m512i field = _mm512_and_si512(bits, _mm512_set1_epi32(0x7fffff));
        const __mmask16 high = _mm512_cmpgt_epi32_mask(field, _mm512_set1_epi32(0x3504f3));
        const __m512 m = _mm512_castsi512_ps(_mm512_mask_sub_epi32(_mm512_or_si512(field, _mm512_set1_epi32(0x3f800000)), high,
                                                                   _mm512_or_si512(field, _mm512_set1_epi32(0x3f800000)),
                                                                   _mm512_set1_epi32(1 << 23)));
        const __m512i biased = _mm512_srli_epi32(bits, 23);
        const __m512 e = _mm512_cvtepi32_ps(_mm512_mask_add_epi32(_mm512_sub_epi32(biased, _mm512_set1_epi32(127)), high,
                                                                  _mm512_sub_epi32(biased, _mm512_set1_epi32(127)),
                                                                  _mm512_set1_epi32(1)));
        const __m512 one = _mm512_set1_ps(1.0f);
        // s = (m - 1) / (m + 1) with the reciprocal's estimate and one Newton step (2^-28).
        const __m512 m1 = _mm512_add_ps(m, one), r14 = _mm512_rcp14_ps(m1);
        const __m512 inv_m1 = _mm512_fmadd_ps(r14, _mm512_fnmadd_ps(m1, r14, one), r14);
        const __m512 sr = _mm512_mul_ps(_mm512_sub_ps(m, one), inv_m1), s2 = _mm512_mul_ps(sr, sr);
        __m512 series = _mm512_fmadd_ps(s2, _mm512_set1_ps(1.0f / 9), _mm512_set1_ps(1.0f / 7));
        series = _mm512_fmadd_ps(s2, series, _mm512_set1_ps(1.0f / 5));
        series = _mm512_fmadd_ps(s2, series, _mm512_set1_ps(1.0f / 3));
        series = _mm512_fmadd_ps(s2, series, one);
        const __m512 log2_fp2 = _mm512_fmadd_ps(_mm512_mul_ps(sr, series), _mm512_set1_ps(2.88539008f), e);
        // lod = log2(footprint) + bias, 0 where that is not finite (sampled_lod).
        const __m512 lod = _mm512_add_ps(_mm512_mul_ps(log2_fp2, _mm512_set1_ps(0.5f)), _mm512_set1_ps(bias));
        _mm512_store_ps(out.lod, _mm512_mask_blend_ps(_mm512_fpclass_ps_mask(lod, 0x01 | 0x08 | 0x10 | 0x80), lod,
                                                      _mm512_setzero_ps()));
        return true;
    }
#pragma GCC diagnostic pop
#endif

    // The loop of both: dots(k, dn, du, dv) gives pixel k's D . n, D . u and D . v.
    template <bool kUv, typename Dots>
    __attribute__((always_inline)) void map(std::size_t count, double* __restrict u, double* __restrict v,
                                            float* __restrict lod, Dots&& dots) const {
        std::uint32_t odd = 0;
        for (std::size_t k = 0; k < count; ++k) {
            double dn, du, dv;
            dots(k, dn, du, dv);
            std::uint32_t normal;
            lod[k] = at<kUv>(dn, du, dv, u + k, v + k, normal);
            odd |= normal ^ 1u;
        }
        if (odd) [[unlikely]]
            for (std::size_t k = 0; k < count; ++k) {
                double dn, du, dv;
                dots(k, dn, du, dv);
                patch(dn, du, dv, lod[k]);
            }
    }

    // One pixel from its D . n, D . u, D . v: uv (kUv) and the level (normal = 0: patch it).
    template <bool kUv>
    __attribute__((always_inline)) float at(double dn, double du, double dv, double* __restrict u,
                                            double* __restrict v, std::uint32_t& normal) const {
        const double kk = 1.0 / dn, t = h * kk;
        if constexpr (kUv) {
            *u = std::max(0.0, std::min((cu + t * du) * inv_width, 1.0));
            *v = std::max(0.0, std::min((cv + t * dv) * inv_height, 1.0));
        }
        return 0.5f * fast_log2f(footprint2(float(t), float(kk), float(du), float(dv)), normal);
    }

    // The squared footprint in texels, max(|dP/dx|^2, |dP/dy|^2) on the axes, in float.
    __attribute__((always_inline)) float footprint2(float t, float kk, float du, float dv) const {
        const float ax = t * fsu * (fxu - fxn * kk * du), bx = t * fsv * (fxv - fxn * kk * dv);
        const float ay = t * fsu * (fyu - fyn * kk * du), by = t * fsv * (fyv - fyn * kk * dv);
        return std::max(ax * ax + bx * bx, ay * ay + by * by);
    }

    // A footprint that fast_log2f cannot take (zero, subnormal, infinite or NaN in float, such
    // as at a grazing angle): its level from the footprint in double and libm's log2.
    void patch(double dn, double du, double dv, float& lod) const {
        std::uint32_t normal;
        at<false>(dn, du, dv, nullptr, nullptr, normal);
        if (normal) return;
        const double kk = 1.0 / dn, t = h * kk;
        const double ax = t * su * (xu - xn * kk * du), bx = t * sv * (xv - xn * kk * dv);
        const double ay = t * su * (yu - yn * kk * du), by = t * sv * (yv - yn * kk * dv);
        lod = float(0.5 * std::log2(std::max(ax * ax + bx * bx, ay * ay + by * by)));
    }

    // log2(x) for a positive normal float without a libm call so the lanes' loop vectorises:
    // the exponent from the bits, the mantissa m in [sqrt(1/2), sqrt(2)) by log2(m) =
    // 2 atanh(s) / ln 2 with s = (m - 1) / (m + 1), |s| < 0.172, to s^9 (about 1e-9 from
    // log2(m)), so the result is log2(x) rounded to float to an ulp or so (in double, as
    // before, its division and series were a tenth of the packet loop). normal = false for
    // zero, subnormal, infinite or NaN x (the value is then meaningless).
    static __attribute__((always_inline)) float fast_log2f(float x, std::uint32_t& normal) {
        const std::uint32_t bits = std::bit_cast<std::uint32_t>(x);
        const std::uint32_t biased = (bits >> 23) & 0xff;
        normal = std::uint32_t(biased != 0) & std::uint32_t(biased != 0xff) & std::uint32_t((bits >> 31) == 0);
        // Mantissa in [1, 2); above sqrt(2) (0x3504f3) halved and the exponent raised by one.
        const std::uint32_t field = bits & 0x7fffffu;
        const std::uint32_t high = std::uint32_t(std::int32_t(field) > std::int32_t(0x3504f3));
        const float m = std::bit_cast<float>((field | 0x3f800000u) - (high << 23));
        const float e = float(std::int32_t(biased + high) - 127);
        const float s = (m - 1.0f) / (m + 1.0f), s2 = s * s;
        const float series = 1.0f + s2 * (1.0f / 3 + s2 * (1.0f / 5 + s2 * (1.0f / 7 + s2 * (1.0f / 9))));
        return e + s * series * 2.88539008f;  // 2 / ln 2
    }
};

// 1 / sqrt(x) for x > 0 to about 1e-7 relative: the hardware estimate and one Newton step
// (a square root and a division per pixel were a tenth of the fused loop).
inline float inverse_sqrt(float x) {
#if defined(__SSE__)
    const float r = _mm_cvtss_f32(_mm_rsqrt_ss(_mm_set_ss(x)));
    return r * (1.5f - 0.5f * x * r * r);
#else
    return 1.0f / std::sqrt(x);
#endif
}

// inverse_sqrt of 16 values in place, in SIMD lanes (the same estimate and Newton step).
inline void inverse_sqrt_16(float* x) {
#if defined(__AVX__)
    for (int k = 0; k < 16; k += 8) {
        const __m256 v = _mm256_load_ps(x + k), r = _mm256_rsqrt_ps(v);
        const __m256 half_v_r2 = _mm256_mul_ps(_mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(0.5f), v), r), r);
        _mm256_store_ps(x + k, _mm256_mul_ps(r, _mm256_sub_ps(_mm256_set1_ps(1.5f), half_v_r2)));
    }
#else
    for (int k = 0; k < 16; ++k) x[k] = inverse_sqrt(x[k]);
#endif
}

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

// A packet's light in SoA lanes: per lane the irradiance E, the albedo and the emission.
struct LaneLight {
    alignas(64) float E[3][16];  // irradiance, per channel
    alignas(64) float a[3][16];  // albedo
    alignas(64) float M[3][16];  // emission
};

// The baked lattice at a packet's 16 lanes in two steps, so that the lattice points' cache
// lines (the blend waited for them) arrive while the packet's other work runs: locate() finds
// each lane's three points and weights and fetches the points, blend() reads them later.
struct LatticeLanes {
    alignas(64) const Vec3f* corner[3][16];
    alignas(64) float weight[3][16];
    alignas(64) std::uint32_t tri[16];
    alignas(64) std::int32_t front[16];

    // Lanes with hit[k] != 0 (Embree's geometry, primitive, barycentrics and geometric normal
    // Ng, and back[k] != 0 where the ray runs along Ng, i.e. sees the side Ng points away
    // from): Gallery's lattice_lerp (the clamps, the cell, the sub-triangle
    // and its weights) in straight loops over the lanes, lanes without a hit reading
    // triangle 0 (ignored). No trapping math, as Gallery's lattice_cells: with it GCC keeps
    // the selects as branches.
    [[gnu::optimize("no-trapping-math"), gnu::noinline]]
    void locate(const BakedLattice& b, const RTCHit16& h, const int* __restrict hit,
                const std::int32_t* __restrict back) {
        const unsigned* __restrict geom_in = h.geomID;
        const unsigned* __restrict prim_in = h.primID;
        const float* __restrict b1_in = h.u;
        const float* __restrict b2_in = h.v;
        alignas(64) std::int32_t segments[16], cell_i[16], cell_j[16], upper_of[16];
        // A lane without a hit holds whatever Embree left in its u, v (NaN or huge after a
        // miss): its cell would index far outside the lattice, and blend() reads every lane.
        alignas(64) float b1[16], b2[16];
        for (int k = 0; k < 16; ++k) {
            const std::uint32_t g = hit[k] ? geom_in[k] : 0u, p = hit[k] ? prim_in[k] : 0u;
            const std::uint32_t t = b.first_triangle[g] + p;
            const Vec3f w = b.normal[t];
            tri[k] = t, segments[k] = std::int32_t(b.segments[t]);
            // The eye sees the front: the normal agrees with Embree's on the side the ray hits.
            front[k] = (w.x * h.Ng_x[k] + w.y * h.Ng_y[k] + w.z * h.Ng_z[k] > 0) != (back[k] != 0);
            b1[k] = hit[k] ? b1_in[k] : 0.0f, b2[k] = hit[k] ? b2_in[k] : 0.0f;
        }
        int k0 = 0;
#if defined(__AVX2__)
        // 8 lanes at once, the same operations (GCC vectorises the loop below with masked
        // stores, which are slow on AMD's cores). Selects are blends; min on int32 is
        // vpminsd; a float to int32 conversion truncates as the casts do.
        for (; k0 < 16; k0 += 8) {
            const __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.0f);
            const __m256i n = _mm256_load_si256(reinterpret_cast<const __m256i*>(segments + k0));
            const __m256i n1 = _mm256_sub_epi32(n, _mm256_set1_epi32(1));
            __m256 c1 = _mm256_load_ps(b1 + k0), c2 = _mm256_load_ps(b2 + k0);
            // c < 0 ? 0 : (1 < c ? 1 : c)
            c1 = _mm256_blendv_ps(_mm256_blendv_ps(c1, one, _mm256_cmp_ps(one, c1, _CMP_LT_OQ)), zero,
                                  _mm256_cmp_ps(c1, zero, _CMP_LT_OQ));
            c2 = _mm256_blendv_ps(_mm256_blendv_ps(c2, one, _mm256_cmp_ps(one, c2, _CMP_LT_OQ)), zero,
                                  _mm256_cmp_ps(c2, zero, _CMP_LT_OQ));
            const __m256 s = _mm256_add_ps(c1, c2);
            const __m256 over = _mm256_cmp_ps(s, one, _CMP_GT_OQ);
            c1 = _mm256_blendv_ps(c1, _mm256_div_ps(c1, s), over);
            c2 = _mm256_blendv_ps(c2, _mm256_div_ps(c2, s), over);
            const __m256 nf = _mm256_cvtepi32_ps(n);
            const __m256 x = _mm256_mul_ps(c1, nf), y = _mm256_mul_ps(c2, nf);
            const __m256i i = _mm256_min_epi32(_mm256_cvttps_epi32(x), n1);
            const __m256i j = _mm256_min_epi32(_mm256_cvttps_epi32(y), _mm256_sub_epi32(n1, i));
            const __m256 ex = _mm256_sub_ps(x, _mm256_cvtepi32_ps(i)), ey = _mm256_sub_ps(y, _mm256_cvtepi32_ps(j));
            __m256 fx = _mm256_blendv_ps(ex, zero, _mm256_cmp_ps(ex, zero, _CMP_LT_OQ));
            __m256 fy = _mm256_blendv_ps(ey, zero, _mm256_cmp_ps(ey, zero, _CMP_LT_OQ));
            const __m256 sum = _mm256_add_ps(fx, fy);
            const __m256 past = _mm256_cmp_ps(sum, one, _CMP_GT_OQ);
            // i + j + 2 <= n, i.e. not (i + j + 2 > n)
            const __m256i room = _mm256_xor_si256(
                _mm256_cmpgt_epi32(_mm256_add_epi32(_mm256_add_epi32(i, j), _mm256_set1_epi32(2)), n),
                _mm256_set1_epi32(-1));
            const __m256 upper = _mm256_and_ps(past, _mm256_castsi256_ps(room));
            const __m256 rescale = _mm256_andnot_ps(upper, past);
            const __m256 inv = _mm256_div_ps(one, sum);
            fx = _mm256_blendv_ps(fx, _mm256_mul_ps(fx, inv), rescale);
            fy = _mm256_blendv_ps(fy, _mm256_mul_ps(fy, inv), rescale);
            _mm256_store_si256(reinterpret_cast<__m256i*>(cell_i + k0), i);
            _mm256_store_si256(reinterpret_cast<__m256i*>(cell_j + k0), j);
            _mm256_store_si256(reinterpret_cast<__m256i*>(upper_of + k0),
                               _mm256_and_si256(_mm256_castps_si256(upper), _mm256_set1_epi32(1)));
            _mm256_store_ps(weight[0] + k0, _mm256_blendv_ps(_mm256_sub_ps(_mm256_sub_ps(one, fx), fy),
                                                            _mm256_sub_ps(_mm256_add_ps(fx, fy), one), upper));
            _mm256_store_ps(weight[1] + k0, _mm256_blendv_ps(fx, _mm256_sub_ps(one, fx), upper));
            _mm256_store_ps(weight[2] + k0, _mm256_blendv_ps(fy, _mm256_sub_ps(one, fy), upper));
        }
#endif
        for (int k = k0; k < 16; ++k) {
            const LatticeCell c = lattice_cell(segments[k], b1[k], b2[k]);
            cell_i[k] = c.i, cell_j[k] = c.j, upper_of[k] = c.upper;
            weight[0][k] = c.w0, weight[1][k] = c.w1, weight[2][k] = c.w2;
        }
        for (int k = 0; k < 16; ++k) {
            const std::uint64_t n = std::uint64_t(segments[k]);
            const std::uint64_t i = std::uint64_t(cell_i[k]), j = std::uint64_t(cell_j[k]);
            const bool upper = upper_of[k] != 0;
            // Rows i and i + 1 of the lattice start at row_i and row_i + n + 1 - i.
            const std::uint64_t row_i = i * (n + 1) - i * (i - 1) / 2, row_next = row_i + (n + 1 - i);
            const std::uint64_t right = row_next + j, up = row_i + j + 1;
            const std::uint64_t e0 = upper ? row_next + j + 1 : row_i + j;
            const std::uint64_t e1 = upper ? up : right, e2 = upper ? right : up;
            const Vec3f* E = (front[k] ? b.front : b.back) + b.offset[tri[k]];
            corner[0][k] = E + e0, corner[1][k] = E + e1, corner[2][k] = E + e2;
        }
        for (int k = 0; k < 16; ++k)
            if (hit[k]) {
                __builtin_prefetch(corner[0][k]);
                __builtin_prefetch(corner[1][k]);
                __builtin_prefetch(corner[2][k]);
            }
    }

    // E = E0 w0 + E1 w1 + E2 w2 per lane (lattice_lerp's order), the albedo and the emission
    // (front side only).
    void blend(const BakedLattice& b, LaneLight& __restrict out) const {
        const Vec3f zero{0.0f, 0.0f, 0.0f};
        for (int k = 0; k < 16; ++k) {
            const Vec3f a = *corner[0][k], c = *corner[1][k], d = *corner[2][k];
            const float w0 = weight[0][k], w1 = weight[1][k], w2 = weight[2][k];
            out.E[0][k] = a.x * w0 + c.x * w1 + d.x * w2;
            out.E[1][k] = a.y * w0 + c.y * w1 + d.y * w2;
            out.E[2][k] = a.z * w0 + c.z * w1 + d.z * w2;
            const std::uint32_t t = tri[k];
            const Vec3f al = b.albedo[t], em = front[k] ? b.emission[t] : zero;
            out.a[0][k] = al.x, out.a[1][k] = al.y, out.a[2][k] = al.z;
            out.M[0][k] = em.x, out.M[1][k] = em.y, out.M[2][k] = em.z;
        }
    }

#if defined(__AVX512F__) && defined(__AVX512DQ__)
// GCC 12 warns that the _mm512_undefined_* sources inside its own AVX-512 intrinsics may be
// used uninitialized (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#pragma GCC diagnostic ignored "-Wuninitialized"
    // locate() and blend() in 16 lanes of one vector each: the arrays gathered with 32-bit
    // float indices (the caller checks lanes16(): 3 x the triangles and the points below
    // 2^31), the cell arithmetic as locate's, the corners' indices in uint32 (n < 2^16, so
    // i (n + 1) and a triangle's (n + 1)(n + 2) / 2 points fit). The same operations in the
    // same order as the lane loops, hence the same floats; lanes without a hit are masked
    // out of the gathers (their values are never read).
    alignas(64) std::int32_t point[3][16];  // float index of each corner in front or back
    __mmask16 hit_lanes = 0, front_lanes = 0;
    int first_lane = 0;  // the first hit lane
    bool one_triangle = false, one_cell = false;  // under every hit lane

    static bool lanes16(const BakedLattice& b) {
        constexpr std::uint64_t kLimit = (std::uint64_t(1) << 31) / 3;
        return b.triangles > 0 && b.triangles < kLimit && b.points < kLimit;
    }

    // lattice_cell's cell in lanes, of clamped barycentrics (c1, c2) on triangles of n
    // segments a side: the cell (i, j), the position in it (x, y, before locate's clamp at
    // 0), and room: whether the cell has an upper sub-triangle (i + j + 2 <= n).
    struct Cells16 {
        __m512i i, j;
        __m512 x, y;
        __mmask16 room;
    };
    static Cells16 cells16(__m512 c1, __m512 c2, __m512i n) {
        const __m512i n1 = _mm512_sub_epi32(n, _mm512_set1_epi32(1));
        const __m512 nf = _mm512_cvtepi32_ps(n);
        const __m512 x = _mm512_mul_ps(c1, nf), y = _mm512_mul_ps(c2, nf);
        Cells16 c;
        c.i = _mm512_min_epi32(_mm512_cvttps_epi32(x), n1);
        c.j = _mm512_min_epi32(_mm512_cvttps_epi32(y), _mm512_sub_epi32(n1, c.i));
        c.x = _mm512_sub_ps(x, _mm512_cvtepi32_ps(c.i)), c.y = _mm512_sub_ps(y, _mm512_cvtepi32_ps(c.j));
        c.room = _mm512_cmple_epi32_mask(_mm512_add_epi32(_mm512_add_epi32(c.i, c.j), _mm512_set1_epi32(2)), n);
        return c;
    }

    void locate16(const BakedLattice& b, const RTCHit16& h, const int* __restrict hit,
                  const std::int32_t* __restrict back) {
        const unsigned* __restrict geom_in = h.geomID;
        const unsigned* __restrict prim_in = h.primID;
        const __m512i hits = _mm512_load_si512(hit);
        const __mmask16 hm = _mm512_test_epi32_mask(hits, hits);
        hit_lanes = hm;
        const __m512i g = _mm512_maskz_loadu_epi32(hm, geom_in), p = _mm512_maskz_loadu_epi32(hm, prim_in);
        // Nearly every packet has one triangle under all its hit lanes (and one lattice cell:
        // a cell spans many pixels). Its data are then read once and broadcast: on these
        // cores a 16-lane gather costs about as much as 16 loads.
        const int k0 = std::countr_zero(unsigned(hm));  // the caller has hits
        first_lane = k0;
        const unsigned g0 = geom_in[k0], p0 = prim_in[k0];
        one_triangle = (_mm512_mask_cmpeq_epi32_mask(hm, g, _mm512_set1_epi32(int(g0))) &
                        _mm512_mask_cmpeq_epi32_mask(hm, p, _mm512_set1_epi32(int(p0)))) == hm;
        __m512i t, n, first;
        __m512 wx, wy, wz;
        if (one_triangle) {
            const std::uint32_t t0 = b.first_triangle[g0] + p0;
            const Vec3f w = b.normal[t0];
            t = _mm512_set1_epi32(int(t0));
            wx = _mm512_set1_ps(w.x), wy = _mm512_set1_ps(w.y), wz = _mm512_set1_ps(w.z);
            n = _mm512_set1_epi32(int(b.segments[t0]));
            first = _mm512_set1_epi32(int(std::uint32_t(b.offset[t0])));
        } else {
            t = _mm512_add_epi32(_mm512_i32gather_epi32(g, b.first_triangle, 4), p);
            const __m512i t3 = _mm512_mullo_epi32(t, _mm512_set1_epi32(3));
            const float* normal = &b.normal->x;
            wx = _mm512_i32gather_ps(t3, normal, 4);
            wy = _mm512_i32gather_ps(_mm512_add_epi32(t3, _mm512_set1_epi32(1)), normal, 4);
            wz = _mm512_i32gather_ps(_mm512_add_epi32(t3, _mm512_set1_epi32(2)), normal, 4);
            n = _mm512_i32gather_epi32(t, b.segments, 4);
            // The triangle's first point: the low word of offset[t] (below 2^31 / 3).
            first = _mm512_i32gather_epi32(_mm512_add_epi32(t, t), b.offset, 4);
        }
        _mm512_store_si512(tri, t);
        const __m512 facing = _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(wx, _mm512_load_ps(h.Ng_x)),
                                                          _mm512_mul_ps(wy, _mm512_load_ps(h.Ng_y))),
                                            _mm512_mul_ps(wz, _mm512_load_ps(h.Ng_z)));
        const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
        const __m512i back_i = _mm512_load_si512(back);
        front_lanes = _mm512_cmp_ps_mask(facing, zero, _CMP_GT_OQ) ^ _mm512_test_epi32_mask(back_i, back_i);
        __m512 c1 = _mm512_maskz_loadu_ps(hm, h.u), c2 = _mm512_maskz_loadu_ps(hm, h.v);
        // c < 0 ? 0 : (1 < c ? 1 : c)
        c1 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(one, c1, _CMP_LT_OQ), c1, one);
        c1 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(c1, zero, _CMP_LT_OQ), c1, zero);
        c2 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(one, c2, _CMP_LT_OQ), c2, one);
        c2 = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(c2, zero, _CMP_LT_OQ), c2, zero);
        const __m512 s = _mm512_add_ps(c1, c2);
        // Barycentrics past the far edge (rare: Embree's rounding) scaled back onto it.
        if (const __mmask16 over = _mm512_cmp_ps_mask(s, one, _CMP_GT_OQ)) {
            c1 = _mm512_mask_div_ps(c1, over, c1, s);
            c2 = _mm512_mask_div_ps(c2, over, c2, s);
        }
        const auto [i, j, ex, ey, room] = cells16(c1, c2, n);
        __m512 fx = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(ex, zero, _CMP_LT_OQ), ex, zero);
        __m512 fy = _mm512_mask_blend_ps(_mm512_cmp_ps_mask(ey, zero, _CMP_LT_OQ), ey, zero);
        const __m512 sum = _mm512_add_ps(fx, fy);
        const __mmask16 past = _mm512_cmp_ps_mask(sum, one, _CMP_GT_OQ);
        const __mmask16 upper = past & room, rescale = past & ~upper;
        if (rescale) {  // rare: only on the far edge's cells
            const __m512 inv = _mm512_div_ps(one, sum);
            fx = _mm512_mask_mul_ps(fx, rescale, fx, inv);
            fy = _mm512_mask_mul_ps(fy, rescale, fy, inv);
        }
        _mm512_store_ps(weight[0], _mm512_mask_blend_ps(upper, _mm512_sub_ps(_mm512_sub_ps(one, fx), fy),
                                                         _mm512_sub_ps(_mm512_add_ps(fx, fy), one)));
        _mm512_store_ps(weight[1], _mm512_mask_blend_ps(upper, fx, _mm512_sub_ps(one, fx)));
        _mm512_store_ps(weight[2], _mm512_mask_blend_ps(upper, fy, _mm512_sub_ps(one, fy)));
        // Rows i and i + 1 of the lattice start at row_i and row_i + n + 1 - i (uint32).
        const __m512i one_i = _mm512_set1_epi32(1);
        const __m512i np1 = _mm512_add_epi32(n, one_i);
        const __m512i tri_i = _mm512_srli_epi32(_mm512_mullo_epi32(i, _mm512_sub_epi32(i, one_i)), 1);
        const __m512i row_i = _mm512_sub_epi32(_mm512_mullo_epi32(i, np1), tri_i);
        const __m512i row_next = _mm512_add_epi32(row_i, _mm512_sub_epi32(np1, i));
        const __m512i right = _mm512_add_epi32(row_next, j), up = _mm512_add_epi32(_mm512_add_epi32(row_i, j), one_i);
        const __m512i e0 = _mm512_mask_blend_epi32(upper, _mm512_add_epi32(row_i, j), _mm512_add_epi32(right, one_i));
        const __m512i e1 = _mm512_mask_blend_epi32(upper, right, up);
        const __m512i e2 = _mm512_mask_blend_epi32(upper, up, right);
        const __m512i three = _mm512_set1_epi32(3);
        const __m512i e[3] = {e0, e1, e2};
        for (int c = 0; c < 3; ++c)
            _mm512_store_si512(point[c], _mm512_mullo_epi32(_mm512_add_epi32(first, e[c]), three));
        // One cell: one triangle, one side, and the same cell and sub-triangle in every lane.
        const __m512i lane0 = _mm512_set1_epi32(k0);
        auto uniform = [&](__m512i v) {
            return _mm512_mask_cmpeq_epi32_mask(hm, v, _mm512_permutexvar_epi32(lane0, v)) == hm;
        };
        auto all_or_none = [&](__mmask16 m) { return (m & hm) == ((m >> k0 & 1) ? hm : 0); };
        one_cell = one_triangle && uniform(i) && uniform(j) && all_or_none(upper) && all_or_none(front_lanes);
        if (one_cell) {
            const float* E = &((front_lanes >> k0 & 1) ? b.front : b.back)->x;
            for (int c = 0; c < 3; ++c) __builtin_prefetch(E + point[c][k0]);
            return;
        }
        for (int k = 0; k < 16; ++k)
            if (hm >> k & 1) {
                const float* E = &((front_lanes >> k & 1) ? b.front : b.back)->x;
                __builtin_prefetch(E + point[0][k]);
                __builtin_prefetch(E + point[1][k]);
                __builtin_prefetch(E + point[2][k]);
            }
    }

    // The common packet in one step instead of locate16 and blend16: all 16 lanes hit one
    // triangle, from one side, inside it (Embree's barycentrics need no clamp) and in at most
    // ten sub-triangles of the lattice's cells (nearly always one, or two across a cell's edge
    // or diagonal, as a row of pixels crosses the lattice along a line; more in a distant
    // view). On a sub-triangle the light is an affine function of the cell coordinates: its
    // three corners read once (scalar loads, no gathers) and two fused multiply-adds per
    // channel and lane, E = c0 + fx (c1 - c0) + fy (c2 - c0) (lower; upper: (c1 + c2 - c0) +
    // fx (c0 - c1) + fy (c0 - c2)), which is lattice_lerp's E0 w0 + E1 w1 + E2 w2 to float
    // rounding. The albedo only with_albedo (a painting's is its texture). Returns false,
    // having written nothing, for any other packet (the caller then takes locate16 and
    // blend16).
    bool light16_cells(const BakedLattice& b, const RTCHit16& h, const std::int32_t* __restrict back,
                       bool with_albedo, LaneLight& __restrict out) {
        const unsigned g0 = h.geomID[0], p0 = h.primID[0];
        const __m512i prim = _mm512_loadu_si512(h.primID);
        if (_mm512_cmpneq_epi32_mask(prim, _mm512_set1_epi32(int(p0)))) return false;
        TriangleCache& c = triangle_cache_;
        if (g0 != c.geom || p0 != c.prim) {  // another triangle: its data
            c.geom = g0, c.prim = p0;
            c.t = std::uint64_t(b.first_triangle[g0]) + p0;
            c.w = b.normal[c.t];
            c.n = std::int32_t(b.segments[c.t]);
            c.front_points = b.front + b.offset[c.t], c.back_points = b.back + b.offset[c.t];
            c.albedo = b.albedo[c.t], c.emission = b.emission[c.t];
        }
        // One triangle: Embree's normal is the same in every lane (lane 0's, w . Ng as locate16's).
        const bool normals_agree = c.w.x * h.Ng_x[0] + c.w.y * h.Ng_y[0] + c.w.z * h.Ng_z[0] > 0;
        const __m512i back_i = _mm512_loadu_si512(back);
        const __mmask16 front = __mmask16(normals_agree ? 0xFFFF : 0) ^ _mm512_test_epi32_mask(back_i, back_i);
        if (front != 0 && front != 0xFFFF) return false;
        const __m512 b1 = _mm512_loadu_ps(h.u), b2 = _mm512_loadu_ps(h.v);
        const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
        // Inside: b1, b2 >= 0 and b1 + b2 <= 1 (false for NaN), so lattice_cell's clamps and
        // its scaling back onto the far edge change nothing.
        const __mmask16 inside = _mm512_cmp_ps_mask(b1, zero, _CMP_GE_OQ) & _mm512_cmp_ps_mask(b2, zero, _CMP_GE_OQ) &
                                 _mm512_cmp_ps_mask(_mm512_add_ps(b1, b2), one, _CMP_LE_OQ);
        if (inside != 0xFFFF) return false;
        // Inside, no lane's position in its cell is negative: locate16's clamp is not needed.
        const auto [i, j, fx, fy, room] = cells16(b1, b2, _mm512_set1_epi32(c.n));
        const __mmask16 past = _mm512_cmp_ps_mask(_mm512_add_ps(fx, fy), one, _CMP_GT_OQ);
        const __mmask16 upper = past & room;
        if (past & ~room) return false;  // on the far edge: lattice_cell scales back onto it
        const bool seen_front = front != 0;
        // The sub-triangle of a lane and the lanes on it.
        auto sub_triangle = [&](int lane, __mmask16& lanes) -> const CellLight& {
            const __m512i at = _mm512_set1_epi32(lane);
            const std::int32_t ci = _mm_cvtsi128_si32(_mm512_castsi512_si128(_mm512_permutexvar_epi32(at, i)));
            const std::int32_t cj = _mm_cvtsi128_si32(_mm512_castsi512_si128(_mm512_permutexvar_epi32(at, j)));
            const bool up = (upper >> lane) & 1;
            lanes = _mm512_cmpeq_epi32_mask(i, _mm512_set1_epi32(ci)) & _mm512_cmpeq_epi32_mask(j, _mm512_set1_epi32(cj)) &
                    (up ? upper : __mmask16(~upper));
            return cell_light(ci, cj, up, seen_front);
        };
        // Lane 0's sub-triangle, then lane 15's, then the first lane left out's in turn (a
        // distant view's pixels lie far apart on the lattice), up to kMaxCells. Each costs a
        // few vector operations; locate16 and blend16 cost 9 to 18 gathers.
        constexpr int kMaxCells = 10;
        __mmask16 covered;
        const CellLight& first = sub_triangle(0, covered);
        __m512 E[3];
        for (int k = 0; k < 3; ++k) E[k] = first.light(k, fx, fy);
        // The lanes not yet covered that lie on lane's sub-triangle, lit from it.
        auto add_cell = [&](int lane) {
            __mmask16 lanes;
            const CellLight& cell = sub_triangle(lane, lanes);
            lanes &= __mmask16(~covered);
            for (int k = 0; k < 3; ++k) E[k] = _mm512_mask_blend_ps(lanes, E[k], cell.light(k, fx, fy));
            covered |= lanes;
        };
        // A straight row crosses each cell once, so a packet's cells are runs of lanes and lane
        // 15's is the other of two. Its lookup does not wait for lane 0's lanes, as the loop's
        // next lane would.
        if (covered != 0xFFFF) add_cell(15);
        for (int cells = 2; covered != 0xFFFF; ++cells) {
            if (cells == kMaxCells) return false;
            add_cell(std::countr_zero(unsigned(__mmask16(~covered))));
        }
        for (int k = 0; k < 3; ++k) _mm512_store_ps(out.E[k], E[k]);
        const Vec3f em = seen_front ? c.emission : Vec3f{0.0f, 0.0f, 0.0f};
        if (with_albedo) {
            _mm512_store_ps(out.a[0], _mm512_set1_ps(c.albedo.x)), _mm512_store_ps(out.a[1], _mm512_set1_ps(c.albedo.y));
            _mm512_store_ps(out.a[2], _mm512_set1_ps(c.albedo.z));
        }
        _mm512_store_ps(out.M[0], _mm512_set1_ps(em.x)), _mm512_store_ps(out.M[1], _mm512_set1_ps(em.y));
        _mm512_store_ps(out.M[2], _mm512_set1_ps(em.z));
        return true;
    }
    // A sub-triangle's light as E = base + fx dx + fy dy, per channel (the coefficients as
    // floats: the multiply-adds take them as broadcast memory operands).
    struct CellLight {
        // Triangle t, cell (i, j), sub-triangle and side in one word: t < 2^30, and
        // 0 <= i, j < n < 2^16 (lanes16 keeps the points, about n^2 / 2 a triangle, below
        // 2^31 / 3).
        static constexpr std::uint64_t kEmpty = ~std::uint64_t(0);
        static std::uint64_t key_of(std::uint64_t t, std::int32_t i, std::int32_t j, bool upper, bool front) {
            return t << 34 | std::uint64_t(std::uint32_t(i)) << 18 | std::uint64_t(std::uint32_t(j)) << 2 |
                   std::uint64_t(upper) << 1 | std::uint64_t(front);
        }
        std::uint64_t key = kEmpty;
        float base[3], dx[3], dy[3];
        // Channel k's light in 16 lanes at cell coordinates (fx, fy).
        __m512 light(int k, __m512 fx, __m512 fy) const {
            return _mm512_fmadd_ps(fy, _mm512_set1_ps(dy[k]), _mm512_fmadd_ps(fx, _mm512_set1_ps(dx[k]), _mm512_set1_ps(base[k])));
        }
    };
    // The last packets' triangle (consecutive packets of a row nearly always share it).
    struct TriangleCache {
        unsigned geom = RTC_INVALID_GEOMETRY_ID, prim = 0;
        std::uint64_t t = 0;
        Vec3f w;  // the triangle's normal
        std::int32_t n = 0;
        const Vec3f *front_points = nullptr, *back_points = nullptr;
        Vec3f albedo, emission;
    } triangle_cache_;
    // The sub-triangles lit lately, direct-mapped by their cell's low bits (a chunk's rows
    // cross the same cells one after another; two entries missed about once a packet in a
    // distant view).
    static constexpr std::size_t kCellSlots = 64;
    CellLight cells_[kCellSlots];
    // The light of sub-triangle (ci, cj, upper) of the cached triangle's lattice, seen from the
    // front or the back: cached, or made from its corners as locate() finds them (rows i and
    // i + 1 start at row_i, row_next), valid until the next call.
    const CellLight& cell_light(std::int32_t ci, std::int32_t cj, bool upper, bool front) {
        TriangleCache& c = triangle_cache_;
        const std::uint64_t key = CellLight::key_of(c.t, ci, cj, upper, front);
        CellLight* slot = &cells_[(std::uint32_t(ci) & 7) << 3 | (std::uint32_t(cj) & 3) << 1 | std::uint32_t(upper)];
        if (slot->key == key) return *slot;
        CellLight& cl = *slot;
        const std::uint64_t nn = std::uint64_t(c.n), i = std::uint64_t(ci), j = std::uint64_t(cj);
        const std::uint64_t row_i = i * (nn + 1) - i * (i - 1) / 2, row_next = row_i + (nn + 1 - i);
        const std::uint64_t right = row_next + j, up = row_i + j + 1;
        const Vec3f* E = front ? c.front_points : c.back_points;
        const Vec3f c0 = E[upper ? row_next + j + 1 : row_i + j];
        const Vec3f c1 = E[upper ? up : right], c2 = E[upper ? right : up];
        auto channel = [&](int k, float a0, float a1, float a2) {
            cl.base[k] = upper ? a1 + a2 - a0 : a0;
            cl.dx[k] = upper ? a0 - a1 : a1 - a0;
            cl.dy[k] = upper ? a0 - a2 : a2 - a0;
        };
        channel(0, c0.x, c1.x, c2.x), channel(1, c0.y, c1.y, c2.y), channel(2, c0.z, c1.z, c2.z);
        cl.key = key;
        return cl;
    }

    void blend16(const BakedLattice& b, LaneLight& __restrict out) const {
        const __mmask16 on_front = hit_lanes & front_lanes, on_back = hit_lanes & ~front_lanes;
        const float *F = &b.front->x, *B = &b.back->x;
        const int k0 = first_lane;
        auto corner = [&](int c, int axis) {
            if (one_cell)
                return _mm512_set1_ps(((front_lanes >> k0 & 1) ? F : B)[point[c][k0] + axis]);
            const __m512i at = _mm512_add_epi32(_mm512_load_si512(point[c]), _mm512_set1_epi32(axis));
            __m512 v = _mm512_setzero_ps();
            if (on_front) v = _mm512_mask_i32gather_ps(v, on_front, at, F, 4);
            if (on_back) v = _mm512_mask_i32gather_ps(v, on_back, at, B, 4);
            return v;
        };
        const __m512 w0 = _mm512_load_ps(weight[0]), w1 = _mm512_load_ps(weight[1]), w2 = _mm512_load_ps(weight[2]);
        float* E[3] = {out.E[0], out.E[1], out.E[2]};
        for (int axis = 0; axis < 3; ++axis)
            _mm512_store_ps(E[axis], _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(corner(0, axis), w0),
                                                                 _mm512_mul_ps(corner(1, axis), w1)),
                                                   _mm512_mul_ps(corner(2, axis), w2)));
        const float *albedo = &b.albedo->x, *emission = &b.emission->x;
        float* A[3] = {out.a[0], out.a[1], out.a[2]};
        float* M[3] = {out.M[0], out.M[1], out.M[2]};
        if (one_triangle) {
            const std::size_t t0 = 3 * std::size_t(tri[k0]);
            for (int axis = 0; axis < 3; ++axis) {
                _mm512_store_ps(A[axis], _mm512_set1_ps(albedo[t0 + axis]));
                _mm512_store_ps(M[axis], _mm512_maskz_mov_ps(on_front, _mm512_set1_ps(emission[t0 + axis])));
            }
            return;
        }
        const __m512i t3 = _mm512_mullo_epi32(_mm512_load_si512(tri), _mm512_set1_epi32(3));
        for (int axis = 0; axis < 3; ++axis) {
            const __m512i at = _mm512_add_epi32(t3, _mm512_set1_epi32(axis));
            _mm512_store_ps(A[axis], _mm512_mask_i32gather_ps(_mm512_setzero_ps(), hit_lanes, at, albedo, 4));
            _mm512_store_ps(M[axis], _mm512_mask_i32gather_ps(_mm512_setzero_ps(), on_front, at, emission, 4));
        }
    }
#pragma GCC diagnostic pop
#endif
};

// Whether a point projects into the same row of both eyes (to float rounding): the same
// orientation and intrinsics, and the eyes apart along their right axis only.
bool rows_align(const Camera& left, const Camera& right) {
    auto same = [](const Vec3d& a, const Vec3d& b) { return length(a - b) <= 1e-12; };
    const Vec3d offset = right.position - left.position;
    const double apart = length(offset);
    return same(left.forward, right.forward) && same(left.up, right.up) && same(left.right, right.right) &&
           left.tan_half_y == right.tan_half_y && left.height == right.height &&
           std::abs(dot(offset, left.up)) <= 1e-9 * apart && std::abs(dot(offset, left.forward)) <= 1e-9 * apart;
}

// A painting pixel's level as sampled: the plane map's with the bias; a non-finite one
// samples level 0.
[[gnu::always_inline]] inline float sampled_lod(float lod, float bias) {
    lod += bias;
    return std::isfinite(lod) ? lod : 0.0f;
}

void check_camera(const Camera& eye) {
    require(eye.width > 0 && eye.height > 0, "display: the eye's resolution must be positive");
    require(std::uint64_t(eye.width) * eye.height < (std::uint64_t(1) << 31),
            "display: at most 2^31 pixels per eye");
}
}  // namespace

void DisplayLighting::light_batch(const LightQuery* queries, std::size_t count,
                                  SurfaceLight* out) const {
    for (std::size_t i = 0; i < count; ++i) {
        const LightQuery& q = queries[i];
        light(q.geom, q.prim, q.p, q.n, out[i]);
    }
}

void DisplayPass::GBuffer::resize(std::uint32_t w, std::uint32_t h, bool keep_light) {
    width = w, height = h;
    const std::size_t n = std::size_t(w) * h;
    geom.resize(n), p.resize(n), lod.resize(n);
    if (keep_light) scale.resize(n), add.resize(n);
}

namespace {
#if defined(__AVX512F__)
// GCC 12's false -Wmaybe-uninitialized in its AVX-512 intrinsics (bug 105593), muted.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
// 16 pixels' channels (R, G, B in lanes) stored interleaved at out[0..47] (the first n pixels'
// at out[0..3n-1]), with two two-source permutes per output vector: R and G into place, then B.
inline void store_rgb16(__m512 R, __m512 G, __m512 B, float* out, std::uint32_t n = 16) {
    struct Indices {
        alignas(64) std::int32_t rg[3][16], b[3][16];
        constexpr Indices() : rg{}, b{} {
            for (int o = 0; o < 3; ++o)
                for (int j = 0; j < 16; ++j) {
                    const int g = 16 * o + j, pixel = g / 3, channel = g % 3;
                    rg[o][j] = channel == 0 ? pixel : (channel == 1 ? 16 + pixel : 0);
                    b[o][j] = channel == 2 ? 16 + pixel : j;
                }
        }
    };
    static constexpr Indices kIdx;
    for (int o = 0; o < 3; ++o) {
        const __m512 rg = _mm512_permutex2var_ps(R, _mm512_load_si512(kIdx.rg[o]), G);
        const __m512 rgb = _mm512_permutex2var_ps(rg, _mm512_load_si512(kIdx.b[o]), B);
        if (n == 16) {
            _mm512_storeu_ps(out + 16 * o, rgb);
        } else {  // the first n pixels only: 3n floats
            const int floats = std::clamp(3 * int(n) - 16 * o, 0, 16);
            _mm512_mask_storeu_ps(out + 16 * o, __mmask16((1u << floats) - 1), rgb);
        }
    }
}

// A packet of 16 painting pixels shaded in lanes from their texels (channels apart, 0..255)
// and light into rgb (16 pixels x 3): the operations of the row's shading of its pending
// pixels in the same order (SrgbCurve's decode; albedo x reflectance; x irradiance / pi;
// + emission), so the same floats.
void shade_packet(const float (&tex)[3][16], const float (&E)[3][16], const float (&M)[3][16],
                  const DisplayOptions& o, const SrgbCurve& srgb, float* __restrict rgb, std::uint32_t n = 16) {
    const __m512 reflectance = _mm512_set1_ps(o.painting_reflectance);
    const __m512 inv_pi = _mm512_set1_ps(kInvPi);
    __m512 L[3];
    for (int c = 0; c < 3; ++c) {
        const __m512 code = _mm512_load_ps(tex[c]);
        const __m512 albedo = o.srgb_albedo
                                  ? _mm512_mul_ps(srgb.decode16(code), reflectance)
                                  : _mm512_mul_ps(_mm512_mul_ps(code, _mm512_set1_ps(1.0f / 255.0f)), reflectance);
        const __m512 scale = _mm512_mul_ps(_mm512_load_ps(E[c]), inv_pi);
        L[c] = _mm512_add_ps(_mm512_mul_ps(albedo, scale), _mm512_load_ps(M[c]));
    }
    store_rgb16(L[0], L[1], L[2], rgb, n);
}

// A packet of 16 pixels on a room surface shaded in lanes into rgb (the first n pixels):
// albedo x irradiance / pi + emission, the operations of the row's per-pixel loop in its
// order, so the same floats; their levels (lod) NaN, as every pixel off the paintings.
void shade_room_packet(const LaneLight& L, float* __restrict rgb, float* __restrict lod, std::uint32_t n = 16) {
    const __m512 inv_pi = _mm512_set1_ps(kInvPi);
    auto radiance = [&](int c) {
        return _mm512_add_ps(_mm512_mul_ps(_mm512_mul_ps(_mm512_load_ps(L.a[c]), _mm512_load_ps(L.E[c])), inv_pi),
                             _mm512_load_ps(L.M[c]));
    };
    store_rgb16(radiance(0), radiance(1), radiance(2), rgb, n);
    const __m512 nan = _mm512_set1_ps(std::numeric_limits<float>::quiet_NaN());
    if (n == 16)  // a whole packet (nearly all): a plain store, a masked one costs twice as much
        _mm512_storeu_ps(lod, nan);
    else
        _mm512_mask_storeu_ps(lod, __mmask16((1u << n) - 1), nan);
}
#pragma GCC diagnostic pop
#endif

// A painting pixel of the row waiting for its texel: radiance = linear albedo x scale + add.
struct PendingPixel {
    std::uint32_t x;
    int placement;
    Vec3f scale, add;
};
}  // namespace

namespace {
// A packet of 16 pixels of the row wholly on one surface whose light is a baked lattice,
// waiting for the row's end: Embree's hits and the side each lane sees, then its light, and
// on a painting its origin's uv and its lanes' offsets and levels, and its texels.
struct DeferredPacket {
    RTCHit16 hit;  // geomID, primID, u, v and Ng (instID unused)
    alignas(64) std::int32_t back[16];
    LaneLight light;
    PacketUv uv;
    alignas(64) float tex[3][16];
    std::uint32_t x0, n;   // its first pixel's column, its pixels (16 but in a short last packet)
    int placement;        // -1: a room surface
    bool mapped, sampled;  // uv, tex hold them
};
// Deferred packets per stage of the row's end: short enough that a batch's data stay in the
// first-level cache, long enough that the packets' latencies overlap.
constexpr std::size_t kStageBatch = 8;

// A worker's per-row arrays (see render_eye), kept between calls in each thread.
struct RowScratch {
    std::vector<DeferredPacket> packets;  // the deferred packets waiting for run_batch
    std::vector<TrilinearLanes> samplers;  // per placement, for frame samplers_frame
    std::uint64_t samplers_frame = 0, samplers_call = 0;  // their frame, and render_eye call
    std::vector<PendingPixel> pending;
    std::vector<PlaneMap::Row> planes;
    std::vector<std::size_t> plane_of;
    std::vector<double> us, vs;
    std::vector<float> lods, texels;
    std::vector<std::uint32_t> rx;
    std::vector<int> rpl;
    std::vector<std::int32_t> rsrc;
    std::vector<double> rsx;  // their screen x
    std::vector<float> rlod;
    // The right eye's edge release: one row of claimed depths (with an infinite depth either
    // side) and the row minima of the last three claim rows (row r in slot r % 3).
    std::vector<float> depths;
    std::array<std::vector<float>, 3> row_min;
    std::array<std::size_t, 3> row_min_of;

    void fit(std::size_t w, bool reused) {
        if (pending.size() < w) pending.resize(w), us.resize(w), vs.resize(w), lods.resize(w);
        if (packets.size() < kStageBatch) packets.resize(kStageBatch);
        if (texels.size() < 3 * w) texels.resize(3 * w);
        if (reused && rx.size() < w) {
            rx.resize(w), rpl.resize(w), rsrc.resize(w), rlod.resize(w);
            rsx.resize(w);
            depths.resize(w + 2);
            for (auto& m : row_min) m.resize(w);
        }
        row_min_of.fill(~std::size_t(0));  // another frame's claims
    }
};

constexpr float kInf = std::numeric_limits<float>::infinity();
// Rows per parallel chunk of one eye's pass alone, the display's and the bare cast's alike:
// 16, so that a chunk's rows run one after another on one core (the texel rows sample16
// fetches ahead for the next screen row are read there, not by the other core) and a chunk's
// set-up is paid once per 16 rows; fewer for a short image, so that each thread still takes
// about 8 chunks (the last chunk's wait stays small).
std::size_t rows_per_chunk(std::size_t height, unsigned threads) {
    const std::size_t workers = threads ? threads : default_threads();
    return std::clamp<std::size_t>(height / (8 * workers), 4, 16);
}
// Rows per chunk of the right eye's pass with reuse: each chunk's first and last claim rows
// are reset after the pass (2 rows in 16), the others by the chunk itself.
constexpr std::size_t kReleaseChunkRows = 16;

// Per pixel of one row of claims, the nearest claimed depth among it and its two row
// neighbours (the separable 3 x 3 minimum's first pass; unclaimed: infinitely far).
void claimed_row_min(const std::uint64_t* __restrict claims, std::size_t w, float* __restrict depths,
                     float* __restrict row_min) {
    depths[0] = depths[w + 1] = kInf;
    for (std::size_t x = 0; x < w; ++x) {
        const std::uint64_t c = claims[x];
        depths[x + 1] = c == kUnclaimed ? kInf : std::bit_cast<float>(std::uint32_t(c >> 32));
    }
    for (std::size_t x = 0; x < w; ++x)
        row_min[x] = std::min(std::min(depths[x], depths[x + 1]), depths[x + 2]);
}

// The edge release of one row of claims (see DisplayPass::reuse): a claim is kept unless its
// depth exceeds the 3 x 3 minimum of claimed depths (the row minima of the rows above, at
// and below) x ratio; source gets the kept claim's left pixel, else -1. Returns the count
// kept; with reset, the row's claims are left unclaimed for the next frame.
std::uint64_t release_claims(std::uint64_t* __restrict claims, const float* up, const float* mid,
                             const float* down, std::size_t w, float ratio,
                             std::int32_t* __restrict source, bool reset) {
    std::uint64_t kept = 0;
    std::size_t x = 0;
#if defined(__AVX2__)
    // 8 claims at once, the same comparisons (GCC keeps the loop below scalar). std::min(a, b)
    // is b < a ? b : a, which _mm256_min_ps(b, a) computes.
    const __m256 vratio = _mm256_set1_ps(ratio);
    const __m256i ones = _mm256_set1_epi64x(-1);
    for (; x + 8 <= w; x += 8) {
        const __m256 nearest = _mm256_min_ps(
            _mm256_loadu_ps(down + x),
            _mm256_min_ps(_mm256_loadu_ps(mid + x), _mm256_loadu_ps(up + x)));
        const __m256i c0 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(claims + x));
        const __m256i c1 = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(claims + x + 4));
        // The claims' high words (depths), low words (left pixels) and unclaimed masks, in
        // pixel order: per 128-bit lane the odd (even) words of c0 and c1, then the 64-bit
        // quarters reordered.
        auto odd_words = [](__m256i a, __m256i b) {
            return _mm256_castpd_si256(_mm256_permute4x64_pd(
                _mm256_castps_pd(_mm256_shuffle_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b),
                                                   _MM_SHUFFLE(3, 1, 3, 1))),
                _MM_SHUFFLE(3, 1, 2, 0)));
        };
        auto even_words = [](__m256i a, __m256i b) {
            return _mm256_castpd_si256(_mm256_permute4x64_pd(
                _mm256_castps_pd(_mm256_shuffle_ps(_mm256_castsi256_ps(a), _mm256_castsi256_ps(b),
                                                   _MM_SHUFFLE(2, 0, 2, 0))),
                _MM_SHUFFLE(3, 1, 2, 0)));
        };
        const __m256 depth = _mm256_castsi256_ps(odd_words(c0, c1));
        const __m256i index = even_words(c0, c1);
        const __m256i unclaimed = odd_words(_mm256_cmpeq_epi64(c0, ones), _mm256_cmpeq_epi64(c1, ones));
        const __m256 far = _mm256_cmp_ps(depth, _mm256_mul_ps(nearest, vratio), _CMP_GT_OQ);
        const __m256 drop = _mm256_or_ps(far, _mm256_castsi256_ps(unclaimed));
        _mm256_storeu_si256(reinterpret_cast<__m256i*>(source + x),
                            _mm256_castps_si256(_mm256_blendv_ps(
                                _mm256_castsi256_ps(index), _mm256_castsi256_ps(ones), drop)));
        kept += 8 - std::uint64_t(std::popcount(unsigned(_mm256_movemask_ps(drop))));
    }
#endif
    for (; x < w; ++x) {
        const float nearest = std::min(std::min(up[x], mid[x]), down[x]);
        const std::uint64_t c = claims[x];
        const bool keep = c != kUnclaimed &&
                          !(std::bit_cast<float>(std::uint32_t(c >> 32)) > nearest * ratio);
        source[x] = keep ? std::int32_t(c & 0xffffffffu) : -1;
        kept += keep;
    }
    if (reset) std::fill_n(claims, w, kUnclaimed);
    return kept;
}

// A fresh number (never 0) for each frame any DisplayPass renders and each render_eye call.
std::uint64_t next_serial() {
    static std::atomic<std::uint64_t> serial{0};
    return serial.fetch_add(1, std::memory_order_relaxed) + 1;
}

RowScratch& row_scratch() {
    thread_local RowScratch scratch;
    return scratch;
}
}  // namespace

double DisplayPass::render_eye(const PaintingSceneView& scene, const DisplayLighting& lighting,
                               const VirtualTexture& vt, const Camera& eye, const DisplayOptions& o,
                               GBuffer& g, const Camera* claim_into, const float* left_rgb,
                               float* rgb, EyeStats& st, const RunRows* run) {
    // A left eye that the right eye reuses: its hits claim right pixels as they are found
    // (ClaimProjection), and its painting pixels keep their light.
    const bool keep_light = claim_into != nullptr;
    const bool keep_hits = hits_kept_;
    const BakedLattice* const baked = lighting.baked_lattice();
#if defined(__AVX512F__) && defined(__AVX512DQ__)
    const bool lanes16 = baked && LatticeLanes::lanes16(*baked);
#else
    constexpr bool lanes16 = false;
#endif
    std::optional<ClaimProjection> claim;
    if (claim_into) claim.emplace(*claim_into, claims_.data());
    const auto t0 = Clock::now();
    const std::uint32_t w = eye.width;
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    const std::size_t paintings = vt.layout().paintings.size();
    std::vector<PlaneMap> maps;
    maps.reserve(scene.paintings.size());
    for (const PaintingPlacement& pp : scene.paintings) maps.emplace_back(pp, eye);
    const GBuffer* left = reusing_ ? &g_[0] : nullptr;
    // The right eye: its claims released row by row just before the row is rendered (the
    // claims of the rows above and below are read, so a worker resets the claims of its
    // chunk's inner rows and the chunks' first and last rows are reset after the pass).
    std::int32_t* const sources = reusing_ ? sources_.data() : nullptr;
    std::uint64_t* const claims = reusing_ ? claims_.data() : nullptr;
    const float release_ratio = 1.0f + o.edge_depth_ratio;
    // The left eye of a pair claims without compare-and-swaps inside its chunks' inner rows
    // (ClaimProjection::claim_rows): chunks as tall as the right eye's.
    const std::size_t chunk_rows = reusing_ || claim_into ? kReleaseChunkRows : rows_per_chunk(eye.height, o.threads);
    const bool rows_aligned = claim_into && rows_align(eye, *claim_into);
    std::atomic<std::uint64_t> reused{0};
    GS_CHECK(!left || left_rgb != nullptr);
    const Vec3f origin(eye.position);
    const SrgbCurve& srgb_decode = srgb_curve();
    std::atomic<std::uint64_t> traced{0}, hits{0}, on_paintings{0};
    std::atomic<std::uint64_t> rays_ticks{0}, vt_ticks{0}, shade_ticks{0}, reuse_ticks{0};
    // Screen x of each column's centre, and past the last column (a short last packet's other
    // lanes, which cast its last ray again: cast_rows' whole_tail) the last's.
    const std::size_t padded_w = (std::size_t(w) + 15) / 16 * 16;
    std::vector<double> column_sx(padded_w);
    for (std::uint32_t x = 0; x < w; ++x) column_sx[x] = eye.screen_x(x + 0.5);
    std::fill(column_sx.begin() + w, column_sx.end(), column_sx[w - 1]);
    // Per column, its screen x less that of its packet's first column (PlaneMap::map_packet).
    std::vector<float> column_ds(padded_w);
    for (std::size_t x = 0; x < padded_w; ++x) column_ds[x] = float(column_sx[x] - column_sx[x & ~std::size_t(15)]);
    // One read lock for the frame: the workers' sampler calls run under it.
    const auto vt_lock = vt.read_lock();
#if defined(__AVX512F__)
    // Each worker makes its packet samplers once per frame and has them forget their cached
    // page entries once per call (this call's read lock).
    const std::uint64_t frame = frame_, call = next_serial();
#endif
    auto rows = [&](std::size_t rb, std::size_t re) {
        // The row's painting pixels waiting for their texels (at most one per column, so
        // arrays of the row's width and a count: no push_back's capacity test per pixel), in
        // this thread's scratch (parallel_for calls this body per 4 rows: allocating the
        // arrays per call cost page faults).
        RowScratch& sc = row_scratch();
        sc.fit(w, left != nullptr);
        std::vector<PendingPixel>& pending = sc.pending;
        std::size_t pending_count = 0;
        std::size_t copied_count = 0;  // the row's reused pixels that kept the left radiance
        std::vector<double>&us = sc.us, &vs = sc.vs;  // u and v apart: the sampler's batches read them densely
        std::vector<float>&lods = sc.lods, &texels = sc.texels;
        // The right eye's reused painting pixels of the row: column, placement, left source,
        // point, direction, and uv and level.
        std::vector<std::uint32_t>& rx = sc.rx;
        std::vector<int>& rpl = sc.rpl;
        std::vector<std::int32_t>& rsrc = sc.rsrc;
        std::vector<double>& rsx = sc.rsx;
        std::vector<float>& rlod = sc.rlod;
        std::size_t current_row = ~std::size_t(0);
        // Per placement, its plane map's Row for the row plane_of[pl] (made when the row first
        // needs it: a room of 40 paintings shows a few in most rows).
        std::vector<PlaneMap::Row>& planes = sc.planes;
        std::vector<std::size_t>& plane_of = sc.plane_of;
        planes.resize(maps.size());
        plane_of.assign(maps.size(), ~std::size_t(0));
        Vec3d row_direction;  // D . forward = 1 at the row's centre, screen x 0
        auto plane = [&](int pl) -> const PlaneMap::Row& {
            const std::size_t p = std::size_t(pl);
            if (plane_of[p] != current_row) {
                planes[p] = maps[p].row(row_direction, eye.right);
                plane_of[p] = current_row;
            }
            return planes[p];
        };
        std::uint64_t traced_count = 0, hit_count = 0, painting_count = 0, reused_count = 0;
        // Thread time per stage: laps between the stages of the fused loop, taken on every
        // kTimedRow-th row only, in stage_ticks (split_wall needs only their proportions; a
        // clock read per stage and packet cost a few percent of the pass).
        constexpr std::size_t kTimedRow = 8;
        std::uint64_t t_rays = 0, t_vt = 0, t_shade = 0, t_reuse = 0;
        bool timed = rb % kTimedRow == 0;
        std::uint64_t mark = stage_ticks();
        auto lap = [&](std::uint64_t& acc) {
            if (!timed) return;
            const std::uint64_t now = stage_ticks();
            acc += now - mark;
            mark = now;
        };
        auto start_row = [&](std::size_t row) {
            if (row == current_row) return;
            current_row = row;
            // The row's directions D = row_direction + screen x along right.
            row_direction = eye.forward + eye.screen_y(row + 0.5) * eye.up;
            pending_count = 0;
        };
#if defined(__AVX512F__)
        // Per placement, the sampler of whole packets on one painting (TrilinearLanes), made
        // once per frame and thread (the frame's eyes share the scene and the VT).
        if (sc.samplers_frame != frame) {
            sc.samplers.clear();
            for (const PaintingPlacement& pp : scene.paintings) sc.samplers.emplace_back(vt, pp.painting);
            sc.samplers_frame = frame, sc.samplers_call = call;
        } else if (sc.samplers_call != call) {
            for (TrilinearLanes& s : sc.samplers) s.forget_tiles();
            sc.samplers_call = call;
        }
        std::vector<TrilinearLanes>& packet_samplers = sc.samplers;
#endif
        std::array<LightQuery, 16> queries;
        std::array<SurfaceLight, 16> lights;
        std::array<std::uint32_t, 16> lane;
        LaneLight lane_light;
        LatticeLanes lattice;

        // The side of each of a packet's hits the eye sees (back: the ray runs along Embree's
        // geometric normal), in SIMD lanes (all 16, hit or not: the lanes are independent).
        auto back_sides = [](const RTCRayHit16& h, std::int32_t* back) {
            for (std::uint32_t k = 0; k < 16; ++k)
                back[k] = -std::int32_t(h.hit.Ng_x[k] * h.ray.dir_x[k] + h.hit.Ng_y[k] * h.ray.dir_y[k] +
                                            h.hit.Ng_z[k] * h.ray.dir_z[k] > 0);
        };
        // The packet's hit points, and their eye-facing unit normals (with_normals), in lanes.
        auto hit_points = [&](const RTCRayHit16& h, const std::int32_t* back, bool with_normals, float* hx,
                              float* hy, float* hz, float* nx, float* ny, float* nz) {
            for (std::uint32_t k = 0; k < 16; ++k) {
                const float t = h.ray.tfar[k];
                hx[k] = origin.x + h.ray.dir_x[k] * t, hy[k] = origin.y + h.ray.dir_y[k] * t;
                hz[k] = origin.z + h.ray.dir_z[k] * t;
            }
            if (!with_normals) return;
            alignas(64) float inv_len[16];
            for (std::uint32_t k = 0; k < 16; ++k) {
                const float gx = h.hit.Ng_x[k], gy = h.hit.Ng_y[k], gz = h.hit.Ng_z[k];
                inv_len[k] = gx * gx + gy * gy + gz * gz;
            }
            inverse_sqrt_16(inv_len);
            for (std::uint32_t k = 0; k < 16; ++k) {
                const float gx = h.hit.Ng_x[k] * inv_len[k], gy = h.hit.Ng_y[k] * inv_len[k],
                            gz = h.hit.Ng_z[k] * inv_len[k];
                nx[k] = back[k] ? -gx : gx, ny[k] = back[k] ? -gy : gy, nz[k] = back[k] ? -gz : gz;
            }
        };

#if defined(__AVX512F__) && defined(__AVX512DQ__)
        // The deferred packets, stage by stage (each stage a short loop over the batch's
        // independent packets, so their latencies overlap; the batch's data stay in the
        // first-level cache): each packet's light (the baked lattice in lanes), shaded at once
        // on a room surface; a painting packet's origin uv, offsets and levels
        // (PlaneMap::map_packet), its texels (TrilinearLanes), its shading. A painting packet
        // the sampler or the map declines joins the row's pending pixels.
        std::size_t batch_count = 0;  // deferred packets waiting in sc.packets
        alignas(64) int all_hits[16];
        std::fill_n(all_hits, 16, -1);
        auto run_batch = [&] {
            const std::size_t row = current_row;
            float* __restrict const lod_row = g.lod.data() + row * w;
            float* __restrict const rgb_row = rgb + 3 * row * w;
            Vec3f* __restrict const scale_row = keep_light ? g.scale.data() + row * w : nullptr;
            Vec3f* __restrict const add_row = keep_light ? g.add.data() + row * w : nullptr;
            // A packet's 16 pixels queued as pending pixels at uv (u, v) and level lod.
            auto pend16 = [&](const DeferredPacket& d, const double* u, const double* v, const float* lod) {
                GS_CHECK(pending_count + d.n <= w);  // one pixel per column and row
                for (std::uint32_t k = 0; k < d.n; ++k) {
                    const std::size_t pc = pending_count++, x = d.x0 + k;
                    PendingPixel& pp = pending[pc];
                    pp.x = std::uint32_t(x), pp.placement = d.placement;
                    pp.scale = Vec3f{d.light.E[0][k], d.light.E[1][k], d.light.E[2][k]} * kInvPi;
                    pp.add = Vec3f{d.light.M[0][k], d.light.M[1][k], d.light.M[2][k]};
                    us[pc] = u[k], vs[pc] = v[k], lods[pc] = lod[k];
                    lod_row[x] = lod[k];
                    if (keep_light) scale_row[x] = pp.scale, add_row[x] = pp.add;
                }
            };
            const std::size_t count = batch_count;
            batch_count = 0;
            for (std::size_t q = 0; q < count; ++q) {
                DeferredPacket& d = sc.packets[q];
                LaneLight& L = d.light;
                if (!lattice.light16_cells(*baked, d.hit, d.back, d.placement < 0, L)) {
                    lattice.locate16(*baked, d.hit, all_hits, d.back);
                    lattice.blend16(*baked, L);
                }
                if (d.placement < 0) shade_room_packet(L, rgb_row + 3 * std::size_t(d.x0), lod_row + d.x0, d.n);
            }
            lap(t_shade);
            for (std::size_t q = 0; q < count; ++q) {
                DeferredPacket& d = sc.packets[q];
                d.mapped = d.sampled = false;
                if (d.placement < 0) continue;
                const std::size_t pl = std::size_t(d.placement);
                d.mapped = packet_samplers[pl].enabled() &&
                           maps[pl].map_packet(plane(d.placement), column_sx[d.x0], column_ds.data() + d.x0,
                                               o.lod_bias, d.uv);
                if (d.mapped) continue;
                // Not a normal footprint (a grazing view): map_columns patches it in double.
                alignas(64) double u[16], v[16];
                alignas(64) float lod[16];
                maps[pl].map_columns<true>(plane(d.placement), 16, column_sx.data() + d.x0, u, v, lod);
                for (std::uint32_t k = 0; k < 16; ++k) lod[k] = sampled_lod(lod[k], o.lod_bias);
                pend16(d, u, v, lod);
            }
            for (std::size_t q = 0; q < count; ++q) {
                DeferredPacket& d = sc.packets[q];
                if (!d.mapped) continue;
                d.sampled = packet_samplers[std::size_t(d.placement)].sample16(d.uv, d.tex[0], d.tex[1], d.tex[2]);
                if (d.sampled) continue;
                alignas(64) double u[16], v[16];
                for (std::uint32_t k = 0; k < 16; ++k) u[k] = d.uv.u0 + d.uv.du[k], v[k] = d.uv.v0 + d.uv.dv[k];
                pend16(d, u, v, d.uv.lod);
            }
            lap(t_vt);
            for (std::size_t q = 0; q < count; ++q) {
                const DeferredPacket& d = sc.packets[q];
                if (!d.sampled) continue;
                shade_packet(d.tex, d.light.E, d.light.M, o, srgb_decode, rgb_row + 3 * std::size_t(d.x0), d.n);
                if (d.n == 16)  // a whole packet (nearly all): one store
                    _mm512_storeu_ps(lod_row + d.x0, _mm512_load_ps(d.uv.lod));
                else
                    std::copy_n(d.uv.lod, d.n, lod_row + d.x0);
                if (keep_light)
                    for (std::uint32_t k = 0; k < d.n; ++k) {
                        Vec3f& sc_k = scale_row[d.x0 + k];
                        sc_k.x = d.light.E[0][k] * kInvPi, sc_k.y = d.light.E[1][k] * kInvPi, sc_k.z = d.light.E[2][k] * kInvPi;
                        Vec3f& add_k = add_row[d.x0 + k];
                        add_k.x = d.light.M[0][k], add_k.y = d.light.M[1][k], add_k.z = d.light.M[2][k];
                    }
                painting_count += d.n;
            }
            lap(t_shade);
        };
#endif

#if defined(__AVX512F__) && defined(__AVX512DQ__)
        // A packet wholly on one surface with its light in the baked lattice (nearly every
        // packet): its hits kept (and the right eye's claims made) now, the rest deferred to
        // run_batch with the next packets (done here, one packet after another between
        // Embree's calls, each stage's latencies stalled the packet).
        auto keep_hits_and_claim = [&](std::size_t row, std::uint32_t i0, std::uint32_t n, const RTCRayHit16& h,
                                       unsigned g0, const std::int32_t* back) {
            alignas(64) float hx[16], hy[16], hz[16], nx[16], ny[16], nz[16];
            hit_points(h, back, bool(claim), hx, hy, hz, nx, ny, nz);
            const std::size_t row_start = row * w + i0;
            if (keep_hits) {
                std::fill_n(g.geom.data() + row_start, n, g0);
                Vec3f* __restrict const p_out = g.p.data() + row_start;
                for (std::uint32_t k = 0; k < n; ++k) p_out[k].x = hx[k], p_out[k].y = hy[k], p_out[k].z = hz[k];
            }
            if (claim) {
                alignas(64) std::uint32_t claim_target[16];
                alignas(64) float claim_depth[16];
                alignas(64) int hit[16];
                for (std::uint32_t k = 0; k < 16; ++k) hit[k] = k < n ? -1 : 0;
                lap(t_shade);
                claim->project16(hx, hy, hz, nx, ny, nz, hit, claim_target, claim_depth);
                claim->claim16(claim_target, claim_depth, std::uint32_t(row_start),
                               claim->claim_rows(rows_aligned, row, rb, re));
                lap(t_reuse);
            }
        };
        auto defer = [&](std::size_t row, std::uint32_t i0, std::uint32_t n, const RTCRayHit16& h, unsigned g0) {
            DeferredPacket& d = sc.packets[batch_count++];
            back_sides(h, d.back);
            std::copy_n(h.hit.geomID, 16, d.hit.geomID), std::copy_n(h.hit.primID, 16, d.hit.primID);
            std::copy_n(h.hit.u, 16, d.hit.u), std::copy_n(h.hit.v, 16, d.hit.v);
            std::copy_n(h.hit.Ng_x, 16, d.hit.Ng_x), std::copy_n(h.hit.Ng_y, 16, d.hit.Ng_y);
            std::copy_n(h.hit.Ng_z, 16, d.hit.Ng_z);
            d.x0 = i0, d.n = n, d.placement = g0 < scene.geom_placement.size() ? scene.geom_placement[g0] : -1;
            traced_count += n, hit_count += n;
            if (keep_hits || claim) keep_hits_and_claim(row, i0, n, h, g0, d.back);
            if (batch_count == kStageBatch) run_batch();
        };
#endif

        // Every packet but the deferred ones: the side each hit sees; the hit points and
        // eye-facing unit normals only where something reads them (the G-buffer, the right
        // eye's claims, a lighting that is not a baked lattice). Out of line, so that the
        // common packet's test and deferral sit in cast_rows' loop without this body's
        // register saves.
        auto other_packet = [&](std::size_t row, std::uint32_t i0, std::uint32_t n, const int* valid,
                                const RTCRayHit16& h) __attribute__((noinline)) {
            alignas(64) float hx[16], hy[16], hz[16], nx[16], ny[16], nz[16];
            alignas(64) std::int32_t back[16];
            back_sides(h, back);
            if (keep_hits || claim || !baked) hit_points(h, back, claim || !baked, hx, hy, hz, nx, ny, nz);
            // The buffers and the counts in restrict locals: through the captured references,
            // every store forced their reload (it might alias them).
            unsigned* __restrict const geom_out = g.geom.data();
            Vec3f* __restrict const p_out = g.p.data();
            float* __restrict const lod_out = g.lod.data();
            float* __restrict const rgb_out = rgb;
            const int* __restrict const placement = scene.geom_placement.data();
            const std::size_t placements = scene.geom_placement.size();
            const std::size_t row_start = row * w + i0;
            alignas(64) int lane_pl[16];  // per hit: its painting placement, -1 for the room
            std::uint32_t m = 0, traced_here = 0;
            // A whole packet on one surface (most packets, with baked light): its lanes need no
            // compaction, and on a painting no gathering of the painting lanes.
            const unsigned g0 = h.hit.geomID[0];
            bool dense = n == 16 && baked && g0 != kNoHit;
            if (dense) {
                int all = -1;
                for (std::uint32_t k = 0; k < 16; ++k) all &= valid[k] & -int(h.hit.geomID[k] == g0);
                dense = all != 0;
            }
            if (dense) {
                const int pl0 = g0 < placements ? placement[g0] : -1;
                if (keep_hits)
                    for (std::uint32_t k = 0; k < 16; ++k) {
                        geom_out[row_start + k] = g0;
                        Vec3f& gp = p_out[row_start + k];
                        gp.x = hx[k], gp.y = hy[k], gp.z = hz[k];
                    }
                for (std::uint32_t k = 0; k < 16; ++k) lane_pl[k] = pl0, lane[k] = k;
                m = traced_here = 16;
            }
            for (std::uint32_t k = 0; k < n && !dense; ++k) {
                if (!valid[k]) continue;
                ++traced_here;
                const std::size_t i = row_start + k;
                const unsigned geom = h.hit.geomID[k];
                if (keep_hits) geom_out[i] = geom;
                if (geom == kNoHit) {
                    rgb_out[3 * i] = rgb_out[3 * i + 1] = rgb_out[3 * i + 2] = 0.0f;
                    lod_out[i] = kNaN;
                    continue;
                }
                // Component stores: a Vec3f copied through the stack stalled on store
                // forwarding (a 12-byte object read back as 8 + 4 bytes).
                if (keep_hits) {
                    Vec3f& gp = p_out[i];
                    gp.x = hx[k], gp.y = hy[k], gp.z = hz[k];
                }
                if (!baked) {
                    LightQuery& q = queries[m];
                    q.geom = geom, q.prim = h.hit.primID[k], q.b1 = h.hit.u[k], q.b2 = h.hit.v[k];
                    q.p.x = hx[k], q.p.y = hy[k], q.p.z = hz[k];
                    q.n.x = nx[k], q.n.y = ny[k], q.n.z = nz[k];
                }
                lane_pl[m] = geom < placements ? placement[geom] : -1;
                lane[m++] = k;
            }
            traced_count += traced_here;
            hit_count += m;
            // The right eye's claims, projected while the hits are in registers and made after
            // the lighting call (their cache lines fetched meanwhile).
            alignas(64) std::uint32_t claim_target[16];
            alignas(64) float claim_depth[16];
            alignas(64) int hit[16];
            for (std::uint32_t k = 0; k < 16; ++k) hit[k] = k < n && valid[k] && h.hit.geomID[k] != kNoHit ? -1 : 0;
            if (claim && m) {
                lap(t_shade);
                claim->project16(hx, hy, hz, nx, ny, nz, hit, claim_target, claim_depth);
                lap(t_reuse);
            }
            // The hits' light per lane: the baked lattice read in lanes (its points fetched
            // now, blended after the plane map below), else the lighting's batch call, its
            // records spread onto their lanes.
            LaneLight& ll = lane_light;
            if (m && lanes16) {
#if defined(__AVX512F__) && defined(__AVX512DQ__)
                lattice.locate16(*baked, h.hit, hit, back);
#endif
            } else if (m && baked) {
                lattice.locate(*baked, h.hit, hit, back);
            } else if (m) {
                lighting.light_batch(queries.data(), m, lights.data());
                for (std::uint32_t j = 0; j < m; ++j) {
                    const SurfaceLight& sl = lights[j];
                    const std::uint32_t k = lane[j];
                    ll.E[0][k] = sl.irradiance.x, ll.E[1][k] = sl.irradiance.y, ll.E[2][k] = sl.irradiance.z;
                    ll.a[0][k] = sl.albedo.x, ll.a[1][k] = sl.albedo.y, ll.a[2][k] = sl.albedo.z;
                    ll.M[0][k] = sl.emission.x, ll.M[1][k] = sl.emission.y, ll.M[2][k] = sl.emission.z;
                }
            }
            lap(t_shade);
            if (claim && m) {
                claim->claim16(claim_target, claim_depth, std::uint32_t(row_start),
                               claim->claim_rows(rows_aligned, row, rb, re));
                lap(t_reuse);
            }
            // Room surfaces shaded here; the painting lanes mapped to uv and level from their
            // columns' screen x in runs of one painting, in SIMD lanes (PlaneMap::map_columns).
            alignas(64) double psx[16], pu[16], pv[16];
            alignas(64) float plod[16];
            alignas(64) std::uint32_t pj[16];
            alignas(64) int ppl[16];
            std::uint32_t np = 0;
            const bool dense_painting = dense && lane_pl[0] >= 0;
            if (dense_painting) {
                for (std::uint32_t k = 0; k < 16; ++k) pj[k] = k, ppl[k] = lane_pl[0];
                maps[std::size_t(lane_pl[0])].map_columns<true>(plane(lane_pl[0]), 16,
                                                                column_sx.data() + i0, pu, pv, plod);
                np = 16;
            }
            for (std::uint32_t j = 0; j < m && !dense_painting; ++j) {
                const std::uint32_t k = lane[j];
                const int pl = lane_pl[j];
                if (pl < 0) continue;
                psx[np] = column_sx[i0 + k];
                pj[np] = j, ppl[np] = pl;
                ++np;
            }
            for (std::uint32_t r0 = 0; r0 < np && !dense_painting;) {
                const int pl = ppl[r0];
                std::uint32_t r1 = r0 + 1;
                while (r1 < np && ppl[r1] == pl) ++r1;
                maps[std::size_t(pl)].map_columns<true>(plane(pl), r1 - r0, psx + r0,
                                                        pu + r0, pv + r0, plod + r0);
                r0 = r1;
            }
            if (m && lanes16) {
#if defined(__AVX512F__) && defined(__AVX512DQ__)
                lattice.blend16(*baked, ll);
#endif
            } else if (m && baked) {
                lattice.blend(*baked, ll);
            }
#if defined(__AVX512F__)
            // A whole packet on one room surface: the loop below in lanes.
            if (dense && !dense_painting) {
                shade_room_packet(ll, rgb_out + 3 * row_start, lod_out + row_start);
                m = 0;  // nothing left for the loop below
            }
#endif
            for (std::uint32_t j = 0; j < m && !dense_painting; ++j) {
                if (lane_pl[j] >= 0) continue;
                const std::uint32_t k = lane[j];
                const std::size_t i = row_start + k;
                const Vec3f L = Vec3f{ll.a[0][k], ll.a[1][k], ll.a[2][k]} * Vec3f{ll.E[0][k], ll.E[1][k], ll.E[2][k]} * kInvPi +
                                Vec3f{ll.M[0][k], ll.M[1][k], ll.M[2][k]};
                rgb_out[3 * i] = L.x, rgb_out[3 * i + 1] = L.y, rgb_out[3 * i + 2] = L.z;
                lod_out[i] = kNaN;
            }
            // The painting pixels' levels (with the bias; a non-finite level samples level 0)
            // stored, their texels queued, and their light kept for the right eye.
            Vec3f* __restrict const scale_out = keep_light ? g.scale.data() : nullptr;
            Vec3f* __restrict const add_out = keep_light ? g.add.data() : nullptr;
            PendingPixel* __restrict const pend = pending.data();
            double* __restrict const us_out = us.data();
            double* __restrict const vs_out = vs.data();
            float* __restrict const lods_out = lods.data();
            const float bias = o.lod_bias;
            std::size_t pc = pending_count;
            GS_CHECK(pc + np <= w);  // one pixel per column and row
            for (std::uint32_t q = 0; q < np; ++q) {
                const std::uint32_t j = pj[q], k = lane[j];
                const std::size_t i = row_start + k;
                const Vec3f scale = Vec3f{ll.E[0][k], ll.E[1][k], ll.E[2][k]} * kInvPi;
                const Vec3f emission{ll.M[0][k], ll.M[1][k], ll.M[2][k]};
                if (keep_light) {
                    scale_out[i].x = scale.x, scale_out[i].y = scale.y, scale_out[i].z = scale.z;
                    add_out[i].x = emission.x, add_out[i].y = emission.y, add_out[i].z = emission.z;
                }
                const float lod = sampled_lod(plod[q], bias);
                lod_out[i] = lod;
                PendingPixel& pp = pend[pc];
                pp.x = i0 + k, pp.placement = ppl[q];
                pp.scale = scale, pp.add = emission;
                us_out[pc] = pu[q], vs_out[pc] = pv[q], lods_out[pc] = lod;
                ++pc;
            }
            pending_count = pc;
            lap(t_vt);
        };
        auto on_packet = [&](std::size_t row, std::uint32_t i0, std::uint32_t n, const int* valid,
                             const RTCRayHit16& h) __attribute__((always_inline)) {
            lap(t_rays);
            start_row(row);
#if defined(__AVX512F__) && defined(__AVX512DQ__)
            if (lanes16) {  // (a short last packet casts all 16 lanes: whole_tail)
                const unsigned g0 = h.hit.geomID[0];
                const __m512i valid16 = _mm512_load_si512(valid);
                if (g0 != kNoHit && _mm512_test_epi32_mask(valid16, valid16) == 0xFFFF &&
                    _mm512_cmpeq_epi32_mask(_mm512_loadu_si512(h.hit.geomID), _mm512_set1_epi32(int(g0))) == 0xFFFF) {
                    defer(row, i0, n, h, g0);
                    return;
                }
            }
#endif
            other_packet(row, i0, n, valid, h);
        };

        // The right eye: the edge release of the row's claims (their sources, the packets'
        // skip mask) from the row minima of the claim rows above, at and below.
        const std::size_t h = eye.height;
        auto on_row_start = [&](std::size_t row) {
            if (!left) return;
            const float* m[3];
            for (int d = 0; d < 3; ++d) {
                const std::size_t r = std::min(h - 1, std::max(row + d, std::size_t(1)) - 1);
                std::vector<float>& slot = sc.row_min[r % 3];
                if (sc.row_min_of[r % 3] != r) {
                    claimed_row_min(claims + r * w, w, sc.depths.data(), slot.data());
                    sc.row_min_of[r % 3] = r;
                }
                m[d] = slot.data();
            }
            // A chunk's first and last claim rows are read by the chunks beside it: reset later.
            reused_count += release_claims(claims + row * w, m[0], m[1], m[2], w, release_ratio,
                                           sources + row * w, rb < row && row + 1 < re);
            lap(t_reuse);
        };

        auto on_row = [&](std::size_t row) {
            lap(t_rays);
            start_row(row);
            // The right eye's claimed pixels: the left hit and its light, the level of this eye
            // at the pixel (along its centre ray, as a traced pixel's), the painting pixels'
            // level in SIMD lanes per run of one painting (PlaneMap::map_columns, as the left
            // eye's packets). The buffers in restrict locals: through the captured references every
            // store forced their reload.
            if (left) {
                const std::int32_t* __restrict src = sources + row * w;
                const unsigned* __restrict lgeom = left->geom.data();
                const Vec3f* __restrict lp = left->p.data();
                const float* __restrict llod = left->lod.data();
                const float* __restrict lrgb = left_rgb;
                unsigned* __restrict geom_out = g.geom.data() + row * w;
                float* __restrict lod_out = g.lod.data() + row * w;
                float* __restrict rgb_out = rgb + 3 * row * w;
                const int* __restrict placement = scene.geom_placement.data();
                const std::size_t placements = scene.geom_placement.size();
                std::uint32_t* __restrict rxs = rx.data();
                int* __restrict rpls = rpl.data();
                std::int32_t* __restrict rsrcs = rsrc.data();
                std::size_t nr = 0, reused_here = 0, copied = 0;
                const float bias = o.lod_bias, tolerance = o.reuse_lod_tolerance;
                // 16 pixels reusing 16 consecutive left pixels on one surface (most of a row:
                // the disparity changes slowly) are copied whole: the left radiance, and on a
                // painting the levels in SIMD lanes and the copy if all agree with the left
                // eye's (else they go the per-pixel way below, as every other pixel).
                auto dense_run = [&](std::uint32_t x0) {
                    const std::int32_t s0 = src[x0];
                    if (s0 < 0) return false;
                    int same = -1;
                    for (std::uint32_t k = 0; k < 16; ++k) same &= -int(src[x0 + k] == s0 + std::int32_t(k));
                    if (!same) return false;
                    const std::size_t si = std::size_t(s0);
                    const unsigned geom = lgeom[si];
                    for (std::uint32_t k = 0; k < 16; ++k) same &= -int(lgeom[si + k] == geom);
                    if (!same) return false;
                    const int pl = geom < placements ? placement[geom] : -1;
                    alignas(64) float lod16[16];
                    if (pl >= 0) {
                        maps[std::size_t(pl)].map_columns<false>(plane(pl), 16, column_sx.data() + x0,
                                                                 nullptr, nullptr, lod16);
                        for (std::uint32_t k = 0; k < 16; ++k) {
                            lod16[k] = sampled_lod(lod16[k], bias);
                            same &= -int(std::abs(llod[si + k] - lod16[k]) <= tolerance);
                        }
                        if (!same) return false;
                        copied += 16;
                    } else {
                        std::fill_n(lod16, 16, kNaN);
                    }
                    std::fill_n(geom_out + x0, 16, geom);  // the points stay in the left buffer
                    std::copy_n(lod16, 16, lod_out + x0);
                    std::copy_n(lrgb + 3 * si, 48, rgb_out + 3 * std::size_t(x0));
                    reused_here += 16;
                    return true;
                };
                for (std::uint32_t x0 = 0; x0 < w; x0 += 16) {
                    const std::uint32_t x1 = std::min(w, x0 + 16);
                    if (x1 - x0 == 16 && dense_run(x0)) continue;
                    for (std::uint32_t x = x0; x < x1; ++x) {
                        const std::int32_t s = src[x];
                        if (s < 0) continue;
                        ++reused_here;
                        const std::size_t si = std::size_t(s);
                        const unsigned geom = lgeom[si];
                        geom_out[x] = geom;  // the point stays in the left buffer (hit_points)
                        const int pl = geom < placements ? placement[geom] : -1;
                        if (pl < 0) {  // the left eye's radiance: the same light, the same albedo
                            rgb_out[3 * x] = lrgb[3 * si], rgb_out[3 * x + 1] = lrgb[3 * si + 1];
                            rgb_out[3 * x + 2] = lrgb[3 * si + 2];
                            lod_out[x] = kNaN;
                            continue;
                        }
                        rxs[nr] = x, rpls[nr] = pl, rsrcs[nr] = s;
                        ++nr;
                    }
                }
                hit_count += reused_here;
                // The level along this eye's ray through the pixel's centre, as the packets
                // compute a traced pixel's (D = row direction + screen x along right, D . forward
                // = 1): no point gathered and no division per pixel.
                double* __restrict sxs = rsx.data();
                for (std::size_t k = 0; k < nr; ++k) sxs[k] = column_sx[rxs[k]];
                float* __restrict lods_r = rlod.data();
                for (std::size_t r0 = 0; r0 < nr;) {
                    const int pl = rpls[r0];
                    std::size_t r1 = r0 + 1;
                    while (r1 < nr && rpls[r1] == pl) ++r1;
                    maps[std::size_t(pl)].map_columns<false>(plane(pl), r1 - r0, sxs + r0, nullptr,
                                                             nullptr, lods_r + r0);
                    r0 = r1;
                }
                // A reused point whose level here is the left eye's to within the tolerance keeps
                // the left eye's sample (the trilinear blend would move by less than that fraction
                // of the two levels' difference); with the left eye's texel, light and shading its
                // radiance is the left pixel's, copied. The others sample their own texel under
                // the left light.
                for (std::size_t k = 0; k < nr; ++k) {
                    const std::uint32_t x = rxs[k];
                    const std::size_t si = std::size_t(rsrcs[k]);
                    const float lod = sampled_lod(lods_r[k], bias);
                    lod_out[x] = lod;
                    if (std::abs(llod[si] - lod) <= tolerance) {
                        rgb_out[3 * x] = lrgb[3 * si], rgb_out[3 * x + 1] = lrgb[3 * si + 1];
                        rgb_out[3 * x + 2] = lrgb[3 * si + 2];
                        ++copied;
                        continue;
                    }
                    // The texel at the left hit's point: D = (p - eye) / ((p - eye) . forward).
                    const Vec3f& p = lp[si];
                    const double tx = p.x - eye.position.x, ty = p.y - eye.position.y, tz = p.z - eye.position.z;
                    const double inv = 1.0 / (tx * eye.forward.x + ty * eye.forward.y + tz * eye.forward.z);
                    const double Dx = tx * inv, Dy = ty * inv, Dz = tz * inv;
                    double u, v;
                    float unused;
                    maps[std::size_t(rpls[k])].map_lanes(1, &Dx, &Dy, &Dz, &u, &v, &unused);
                    const std::size_t q = pending_count++;
                    GS_CHECK(q < w);  // one pixel per column and row
                    PendingPixel& pp = pending[q];
                    pp.x = x, pp.placement = rpls[k];
                    us[q] = u, vs[q] = v, lods[q] = lod;
                    pp.scale = left->scale[si], pp.add = left->add[si];
                }
                copied_count += copied;
            }
#if defined(__AVX512F__) && defined(__AVX512DQ__)
            if (batch_count) run_batch();
#endif
            // Runs of one painting sampled in one call.
            for (std::size_t k0 = 0; k0 < pending_count;) {
                const int pl = pending[k0].placement;
                std::size_t k1 = k0 + 1;
                while (k1 < pending_count && pending[k1].placement == pl) ++k1;
                SampleRequest r;
                r.painting = scene.paintings[std::size_t(pl)].painting;
                require(r.painting < paintings, "display: a painting of the scene is not in "
                                                "the virtual texture");
                r.u = us.data() + k0, r.v = vs.data() + k0, r.uv_stride = 1;
                r.lod = lods.data() + k0;
                r.count = k1 - k0;
                r.filter = Filter::Trilinear;
                r.out = texels.data() + 3 * k0;
                sample_serial_locked(vt, r);
                k0 = k1;
            }
            lap(t_vt);
            // The Gallery's order of operations (its sRGB curve is exact, ours tabulated); on
            // restrict locals (stores through rgb might otherwise alias the arrays' pointers).
            {
                const PendingPixel* __restrict pend = pending.data();
                const float* __restrict tex = texels.data();
                float* __restrict rgb_row = rgb + 3 * row * w;
                const float reflectance = o.painting_reflectance;
                const std::size_t count = pending_count;
                if (o.srgb_albedo) {
                    for (std::size_t k = 0; k < count; ++k) {
                        const PendingPixel& q = pend[k];
                        const float* a = tex + 3 * k;
                        const Vec3f albedo =
                            Vec3f{srgb_decode(a[0]), srgb_decode(a[1]), srgb_decode(a[2])} * reflectance;
                        const Vec3f L = albedo * q.scale + q.add;
                        float* out = rgb_row + 3 * std::size_t(q.x);
                        out[0] = L.x, out[1] = L.y, out[2] = L.z;
                    }
                } else {
                    for (std::size_t k = 0; k < count; ++k) {
                        const PendingPixel& q = pend[k];
                        const float* a = tex + 3 * k;
                        const Vec3f albedo = Vec3f{a[0], a[1], a[2]} * (1.0f / 255.0f) * reflectance;
                        const Vec3f L = albedo * q.scale + q.add;
                        float* out = rgb_row + 3 * std::size_t(q.x);
                        out[0] = L.x, out[1] = L.y, out[2] = L.z;
                    }
                }
            }
            painting_count += pending_count + copied_count;
            copied_count = 0;
            lap(t_shade);
            timed = (row + 1) % kTimedRow == 0;
            if (timed) mark = stage_ticks();
        };

        cast_rows(scene.handle, eye, rb, re, sources, lanes16, on_row_start, on_packet, on_row);
        traced.fetch_add(traced_count, std::memory_order_relaxed);
        hits.fetch_add(hit_count, std::memory_order_relaxed);
        on_paintings.fetch_add(painting_count, std::memory_order_relaxed);
        rays_ticks.fetch_add(t_rays, std::memory_order_relaxed);
        vt_ticks.fetch_add(t_vt, std::memory_order_relaxed);
        shade_ticks.fetch_add(t_shade, std::memory_order_relaxed);
        reuse_ticks.fetch_add(t_reuse, std::memory_order_relaxed);
        reused.fetch_add(reused_count, std::memory_order_relaxed);
    };
    if (run)
        (*run)(chunk_rows, std::cref(rows));
    else
        parallel_for(eye.height, chunk_rows, rows, o.threads);
    if (left) {  // the chunks' first and last claim rows, left unclaimed for the next frame
        for (std::size_t r0 = 0; r0 < eye.height; r0 += chunk_rows) {
            std::fill_n(claims_.data() + r0 * w, w, kUnclaimed);
            const std::size_t last = std::min<std::size_t>(eye.height, r0 + chunk_rows) - 1;
            std::fill_n(claims_.data() + last * w, w, kUnclaimed);
        }
        claims_clear_ = true;
        st.reused = reused.load();
    }
    st.traced = traced.load();
    st.hits = hits.load();
    st.painting_pixels = on_paintings.load();
    // In ticks until split_wall turns them into shares of the pass's wall time.
    st.rays_seconds = double(rays_ticks.load());
    st.vt_seconds = double(vt_ticks.load());
    st.shade_seconds = double(shade_ticks.load());
    st.reuse_seconds = double(reuse_ticks.load());  // the claims, or the edge release
    return seconds_since(t0);
}

namespace {
// The stages interleave in each thread: a pass's wall time is split among the eyes' stages in
// the proportion of the timed rows' thread time in each.
void split_wall(double wall, std::initializer_list<EyeStats*> eyes) {
    double sum = 0;
    for (const EyeStats* st : eyes) sum += st->total_seconds();
    const double f = sum > 0 ? wall / sum : 0.0;
    for (EyeStats* st : eyes)
        st->rays_seconds *= f, st->vt_seconds *= f, st->shade_seconds *= f, st->reuse_seconds *= f;
}

}  // namespace

void DisplayPass::render(const PaintingSceneView& scene, const DisplayLighting& lighting,
                         const VirtualTexture& vt, const Camera& world_eye, const DisplayOptions& o,
                         float* rgb) {
    const std::scoped_lock lock(mutex_);
    require(scene.handle != nullptr, "display: the scene has no BVH");
    require(rgb != nullptr, "display: no output image");
    check_camera(world_eye);
    const Camera eye = world_eye.moved(-scene.origin);  // into the BVH's coordinates
    origin_ = scene.origin;
    GBuffer& g = g_[0];
    g.resize(eye.width, eye.height, false);
    EyeStats& st = stats_[0] = EyeStats{};
    st.pixels = std::uint64_t(eye.width) * eye.height;
    reusing_ = false;
    hits_kept_ = o.keep_hit_points;
    frame_ = next_serial();
    split_wall(render_eye(scene, lighting, vt, eye, o, g, nullptr, nullptr, rgb, st), {&st});
    sources_.clear();
}

void DisplayPass::render_stereo(const PaintingSceneView& scene, const DisplayLighting& lighting,
                                const VirtualTexture& vt, const Camera& world_left,
                                const Camera& world_right, bool use_reuse, const DisplayOptions& o,
                                float* left_rgb, float* right_rgb) {
    const std::scoped_lock lock(mutex_);
    require(scene.handle != nullptr, "display: the scene has no BVH");
    require(left_rgb != nullptr && right_rgb != nullptr, "display: no output image");
    check_camera(world_left);
    check_camera(world_right);
    // Into the BVH's coordinates (both eyes by the same offset: the reuse is unchanged).
    const Camera left = world_left.moved(-scene.origin), right = world_right.moved(-scene.origin);
    origin_ = scene.origin;
    require(left.width == right.width && left.height == right.height,
            "display: both eyes need the same resolution");
    require(std::isfinite(o.edge_depth_ratio) && o.edge_depth_ratio >= 0,
            "display: edge_depth_ratio must be finite and >= 0");
    require(std::isfinite(o.reuse_lod_tolerance) && o.reuse_lod_tolerance >= 0,
            "display: reuse_lod_tolerance must be finite and >= 0");
    reusing_ = false;
    hits_kept_ = true;
    frame_ = next_serial();
    const std::size_t n = std::size_t(right.width) * right.height;
    if (use_reuse) {
        // The last frame's right eye left every claim unclaimed again (no 8-byte fill of the
        // image per frame); after a resize or an interrupted frame they are filled here.
        if (!claims_clear_ || claims_.size() != n) claims_.assign(n, kUnclaimed);
        claims_clear_ = false;
        sources_.resize(n);  // written by the right eye's rows (the edge release)
    }
    GBuffer& gl = g_[0];
    gl.resize(left.width, left.height, use_reuse);
    EyeStats& sl = stats_[0] = EyeStats{};
    sl.pixels = std::uint64_t(left.width) * left.height;
    GBuffer& gr = g_[1];
    gr.resize(right.width, right.height, false);
    EyeStats& sr = stats_[1] = EyeStats{};
    sr.pixels = std::uint64_t(right.width) * right.height;
    if (!use_reuse) {
        sources_.clear();
        split_wall(render_eye(scene, lighting, vt, left, o, gl, nullptr, nullptr, left_rgb, sl), {&sl});
        split_wall(render_eye(scene, lighting, vt, right, o, gr, nullptr, nullptr, right_rgb, sr), {&sr});
        return;
    }
    // The right eye with reuse. Where a point projects into the same row of both eyes, the
    // right eye's rows need only the left rows beside them: both eyes' chunks run in one
    // wavefront (parallel_wavefront), the right eye's render_eye set up inside the left one's so
    // that both passes' rows are ready together. Otherwise the whole left eye first.
    const bool interleave = o.interleave_eyes && rows_align(left, right);
    auto right_eye_pass = [&](const RunRows* run) {
        reusing_ = true;
        try {
            const double w = render_eye(scene, lighting, vt, right, o, gr, nullptr, left_rgb, right_rgb, sr, run);
            if (!run) split_wall(w, {&sr});
        } catch (...) {
            reusing_ = false;
            throw;
        }
        reusing_ = false;
    };
    const RunRows run_left = [&](std::size_t chunk_rows, const RowsBody& left_rows) {
        const RunRows run_right = [&](std::size_t right_chunk_rows, const RowsBody& right_rows) {
            GS_CHECK(right_chunk_rows == chunk_rows);
            // The right eye's chunk reads the left eye's claims on its rows and the rows
            // beside them (a left pixel claims within a row of its own), and the left rows
            // there; run right after the left chunks beside it, they are still in cache (after
            // a whole left eye, 1800 x 1920's 27 MB of claims and 41 MB of left image came
            // back from memory).
            const std::size_t n = left.height;
            parallel_wavefront((n + chunk_rows - 1) / chunk_rows,
                               [&](std::size_t c) { left_rows(c * chunk_rows, std::min(n, (c + 1) * chunk_rows)); },
                               [&](std::size_t c) { right_rows(c * chunk_rows, std::min(n, (c + 1) * chunk_rows)); },
                               o.threads);
        };
        right_eye_pass(&run_right);
    };
    const double wall = render_eye(scene, lighting, vt, left, o, gl, &right, nullptr, left_rgb, sl,
                                   interleave ? &run_left : nullptr);
    if (interleave) {
        split_wall(wall, {&sl, &sr});  // one wall time for both eyes' interleaved rows
    } else {
        split_wall(wall, {&sl});
        right_eye_pass(nullptr);
    }
    // The left eye's claims on right pixels are the right eye's reuse work.
    sr.reuse_seconds += sl.reuse_seconds;
    sl.reuse_seconds = 0;
}

EyeStats DisplayPass::left_stats() const {
    const std::scoped_lock lock(mutex_);
    return stats_[0];
}

EyeStats DisplayPass::right_stats() const {
    const std::scoped_lock lock(mutex_);
    return stats_[1];
}

std::vector<std::int32_t> DisplayPass::reuse_sources() const {
    const std::scoped_lock lock(mutex_);
    return sources_;
}

std::vector<float> DisplayPass::hit_points(int eye) const {
    const std::scoped_lock lock(mutex_);
    require(eye == 0 || eye == 1, "eye must be 0 (left) or 1 (right)");
    require(hits_kept_, "display: the last render kept no hit points (keep_hit_points=False)");
    const GBuffer& g = g_[eye];
    std::vector<float> out(3 * g.geom.size(), std::numeric_limits<float>::quiet_NaN());
    // A reused right pixel's point is its left source's.
    const bool reused = eye == 1 && sources_.size() == g.geom.size();
    for (std::size_t i = 0; i < g.geom.size(); ++i) {
        if (g.geom[i] == kNoHit) continue;
        const Vec3f& local = reused && sources_[i] >= 0 ? g_[0].p[std::size_t(sources_[i])] : g.p[i];
        const Vec3f p(Vec3d(local) + origin_);  // in world coordinates
        out[3 * i] = p.x, out[3 * i + 1] = p.y, out[3 * i + 2] = p.z;
    }
    return out;
}

std::vector<float> DisplayPass::lods(int eye) const {
    const std::scoped_lock lock(mutex_);
    require(eye == 0 || eye == 1, "eye must be 0 (left) or 1 (right)");
    return g_[eye].lod;
}

float* check_output_image(const OutputImage& image, const Camera& eye, const char* what) {
    // Messages appended piecewise (GCC 12 warns falsely on literal + std::string&&).
    auto message = [&](const char* problem) {
        std::string m(what);
        m += problem;
        return m;
    };
    require(image.data != nullptr, message(": no array"));
    require(image.float32, message(": must be float32"));
    require(image.writable, message(": must be writable"));
    if (!(image.ndim == 3 && image.shape[0] == std::int64_t(eye.height) &&
          image.shape[1] == std::int64_t(eye.width) && image.shape[2] == 3)) {
        std::string m = message(": must have shape (");
        m += std::to_string(eye.height);
        m += ", ";
        m += std::to_string(eye.width);
        m += ", 3)";
        throw InvalidArgument(m);
    }
    if (image.strides)
        require(image.strides[2] == 1 && image.strides[1] == 3 &&
                    image.strides[0] == 3 * std::int64_t(eye.width),
                message(": must be C-contiguous"));
    return static_cast<float*>(image.data);
}

void check_disjoint_images(const float* a, const float* b, std::size_t floats) {
    require(a + floats <= b || b + floats <= a, "display: the two eyes' images share memory");
}

double cast_primary_rays(RTCScene scene, const Camera& eye, unsigned threads, std::uint64_t* hits) {
    require(scene != nullptr, "cast_primary_rays: the scene has no BVH");
    check_camera(eye);
    const auto t0 = Clock::now();
    std::atomic<std::uint64_t> total{0};
    parallel_for(eye.height, rows_per_chunk(eye.height, threads), [&](std::size_t rb, std::size_t re) {
        std::uint64_t count = 0;
        cast_rows(scene, eye, rb, re, nullptr, false, [](std::size_t) {},
                  [&](std::size_t, std::uint32_t, std::uint32_t n,
                                                   const int*, const RTCRayHit16& h) {
            for (std::uint32_t k = 0; k < n; ++k) count += h.hit.geomID[k] != kNoHit;
        }, [](std::size_t) {});
        total.fetch_add(count, std::memory_order_relaxed);
    }, threads);
    if (hits) *hits = total.load();
    return seconds_since(t0);
}

}  // namespace gigascroll
