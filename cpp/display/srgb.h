// sRGB decoding (IEC 61966-2-1), the one place for it: srgb_to_linear is the curve itself
// (the definition, the per-pixel reference's and the bake's), SrgbCurve its fast form for the
// display pass's filtered texels (scalar and 16 lanes, the same floats) and srgb_code_table its
// tabulated form for a sampled 8-bit code (the photon map's painting albedo).
#pragma once
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "common/lanes.h"

namespace gigascroll {

// The linear value of an sRGB-encoded component in [0, 1] (IEC 61966-2-1).
inline float srgb_to_linear(float c) {
    return c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
}

// srgb_to_linear(c / 255) of a sampled component c in [0, 255], from a table: exact at whole
// 8-bit values (a uniform painting), linear between them otherwise (within 6e-6: the curve's
// second derivative is below 3). pow per texel was a quarter of a small light() call.
inline float srgb_code_table(float c) {
    static const auto table = [] {
        std::array<float, 257> t{};
        for (int k = 0; k < 256; ++k) t[k] = srgb_to_linear(float(k) / 255.0f);
        t[256] = t[255];
        return t;
    }();
    if (!(c >= 0)) return 0;
    if (!(c < 255)) return table[255];
    const auto k = std::size_t(c);
    const float f = c - float(k);
    return table[k] + (table[k + 1] - table[k]) * f;
}

// sRGB-encoded 0..255 to linear [0, 1] (IEC 61966-2-1) of a filtered (fractional) code: the
// linear segment below code 10.31475 (0.04045 x 255) exactly, above it a quartic per 16 codes
// (Chebyshev interpolation of the exact curve, float coefficients, Horner with fused
// multiply-adds), to 6e-8 absolute and 1.2e-6 relative. One text for every width (decode):
// the coefficients by five in-register lookups where a table took two gathers per channel (a
// 16-lane gather costs as much as 16 loads on the cores this runs on); pow() per pixel was a
// third of the shading.
struct SrgbCurve {
    static constexpr int kSegments = 16;              // of 16 codes each
    static constexpr float kLinearEnd = 10.31475f;    // 0.04045 x 255
    static constexpr float kLinearScale = float(1.0 / (255.0 * 12.92));
    // Per power of t (t = code - the segment's centre), per segment.
    alignas(64) float coef[5][kSegments];

    static double exact(double code) {
        const double c = code / 255.0;
        return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
    }
    SrgbCurve() {
        constexpr int kDegree = 4;
        for (int s = 0; s < kSegments; ++s) {
            const double centre = 16.0 * s + 8.0;
            const double a = s == 0 ? double(kLinearEnd) : 16.0 * s, b = std::min(16.0 * (s + 1), 255.0);
            // The exact curve at the Chebyshev nodes of [a, b], its interpolating polynomial in
            // Newton's form, expanded into powers of t = code - centre.
            double x[kDegree + 1], d[kDegree + 1];
            for (int k = 0; k <= kDegree; ++k) {
                const double node = std::cos(3.14159265358979323846 * (2 * k + 1) / (2 * (kDegree + 1)));
                x[k] = 0.5 * (a + b) + 0.5 * (b - a) * node - centre;
                d[k] = exact(x[k] + centre);
            }
            for (int j = 1; j <= kDegree; ++j)
                for (int k = kDegree; k >= j; --k) d[k] = (d[k] - d[k - 1]) / (x[k] - x[k - j]);
            double poly[kDegree + 1] = {};
            for (int j = kDegree; j >= 0; --j) {  // poly = poly x (t - x[j]) + d[j]
                for (int k = kDegree; k >= 1; --k) poly[k] = poly[k - 1] - x[j] * poly[k];
                poly[0] = d[j] - x[j] * poly[0];
            }
            for (int k = 0; k <= kDegree; ++k) coef[k][s] = float(poly[k]);
        }
    }
    // The decode of W codes: the segment s = floor(c / 16) needs no clamp (c <= 255), and
    // t = (c - 8) - 16 s in one fused step is exact, as c - (16 s + 8) is, wherever the
    // polynomial is taken (c > 10.3: c - 8 is a multiple of c's last place). A NaN code
    // decodes to 0.
    template <int W>
    typename Lanes<W>::F decode(typename Lanes<W>::F code) const {
        using F = typename Lanes<W>::F;
        const F c = min(max(code, F(0.0f)), F(255.0f));
        const F s_f = floor(c * F(1.0f / 16.0f));
        const auto s = to_int(s_f);
        const F t = fnma(s_f, F(16.0f), c - F(8.0f));
        F p = lookup16(coef[4], s);
        for (int k = 3; k >= 0; --k) p = fma(p, t, lookup16(coef[k], s));
        return Lanes<W>::select(c <= F(kLinearEnd), c * F(kLinearScale), p);
    }
    float operator()(float code) const { return decode<1>(Lanes<1>::F(code)).v; }
};
// The one curve of the process (made on first use).
inline const SrgbCurve& srgb_curve() {
    static const SrgbCurve curve;
    return curve;
}

}  // namespace gigascroll
