// The "map" step of the display pass: a painting's plane as one eye sees it, so that a pixel's
// painting coordinates and level of detail are a few multiply-adds on its ray direction.
#pragma once
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "common/lanes.h"
#include "common/vec3.h"
#include "sampling/sampler.h"
#include "views/camera.h"
#include "views/exhibition.h"

namespace gigascroll {
namespace display {

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

    // A packet of 16 columns from screen x s0 (ds[k]: column k's screen x less s0) as
    // TrilinearLanes takes it: lane 0's uv in double, not clamped (the sampler declines a
    // packet that reaches the painting's edge), the lanes' offsets from it in float, and each
    // lane's level plus bias (sampled_lod). The offset of column s from s0 is
    // du = (s - s0) h (qu rn - ru qn) / (width D.n(s) D.n(s0)) (the same for v): the
    // difference of two uv's without their cancellation, to float's relative precision. The
    // level is footprint2's of t, 1 / (D . n), D . u and D . v in float, as map_columns'.
    // False (out part written) where a footprint is not a normal float: the caller then
    // takes map_columns, which patches it in double. W lanes at a time (common/lanes.h).
    template <int W = kWidest>
    bool map_packet(const Row& r, double s0, const float* ds, float bias, PacketUv& out) const {
        using F = typename Lanes<W>::F;
        const double dn0 = r.rn + s0 * r.qn, du0 = r.ru + s0 * r.qu, dv0 = r.rv + s0 * r.qv;
        const double kk0 = 1.0 / dn0, t0 = h * kk0;
        out.u0 = (cu + t0 * du0) * inv_width, out.v0 = (cv + t0 * dv0) * inv_height;
        const F du_scale(float(h * inv_width * (r.qu * r.rn - r.ru * r.qn) * kk0));
        const F dv_scale(float(h * inv_height * (r.qv * r.rn - r.rv * r.qn) * kk0));
        for (int k = 0; k < 16; k += W) {
            const F S = F::load(ds + k);
            const F dn = fma(S, F(float(r.qn)), F(float(dn0)));
            const F kk = F(1.0f) / dn;
            const F S_kk = S * kk;
            (S_kk * du_scale).store(out.du + k);
            (S_kk * dv_scale).store(out.dv + k);
            // footprint2 in lanes.
            const F t = F(float(h)) * kk;
            const F Du = fma(S, F(float(r.qu)), F(float(du0)));
            const F Dv = fma(S, F(float(r.qv)), F(float(dv0)));
            const F kDu = kk * Du, kDv = kk * Dv;
            const F tu = t * F(fsu), tv = t * F(fsv);
            auto term = [](F scale, float a, float b, F kd) { return scale * fnma(F(b), kd, F(a)); };  // scale (a - b kd)
            const F ax = term(tu, fxu, fxn, kDu), bx = term(tv, fxv, fxn, kDv);
            const F ay = term(tu, fyu, fyn, kDu), by = term(tv, fyv, fyn, kDv);
            const F fp2 = max(fma(ax, ax, bx * bx), fma(ay, ay, by * by));
            // zero, subnormal, infinite, NaN or negative: refused.
            if (any<W>(not_positive_normal(fp2))) return false;
            // lod = log2(footprint) + bias, 0 where that is not finite (sampled_lod).
            const F lod = log2_lanes<W>(fp2) * F(0.5f) + F(bias);
            Lanes<W>::select(not_finite(lod), F(0.0f), lod).store(out.lod + k);
        }
        return true;
    }

    // fast_log2f in lanes, of positive normal floats: the same steps but for s = (m - 1) /
    // (m + 1), taken with the reciprocal's estimate and one Newton step (2^-28).
    template <int W>
    static typename Lanes<W>::F log2_lanes(typename Lanes<W>::F x) {
        using L = Lanes<W>;
        using F = typename L::F;
        using I = typename L::I;
        const I b = bits(x);
        const I field = b & I(0x7fffff);
        const auto high = field > I(0x3504f3);
        const I mantissa = field | I(0x3f800000);
        const F m = L::from_bits(L::select(high, mantissa - I(1 << 23), mantissa));
        const I exponent = srl(b, 23) - I(127);
        const F e = L::to_float(L::select(high, exponent + I(1), exponent));
        const F one(1.0f);
        const F sr = (m - one) * reciprocal(m + one), s2 = sr * sr;
        F series = fma(s2, F(1.0f / 9), F(1.0f / 7));
        series = fma(s2, series, F(1.0f / 5));
        series = fma(s2, series, F(1.0f / 3));
        series = fma(s2, series, one);
        return fma(sr * series, F(2.88539008f), e);
    }

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

// A painting pixel's level as sampled: the plane map's with the bias; a non-finite one
// samples level 0.
[[gnu::always_inline]] inline float sampled_lod(float lod, float bias) {
    lod += bias;
    return std::isfinite(lod) ? lod : 0.0f;
}

}  // namespace display
}  // namespace gigascroll
