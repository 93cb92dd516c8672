// The display's sRGB decode against the exact IEC 61966-2-1 curve in double (pow), over every
// 1/64 of a code, and its lanes at every width the host has against the scalar form bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "display/srgb.h"

using namespace gigascroll;

namespace {

double exact_srgb(double code) {
    const double c = code / 255.0;
    return c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4);
}

}  // namespace

TEST(SrgbCurve, FollowsTheExactCurveToAMillionth) {
    const SrgbCurve& curve = srgb_curve();
    double worst_abs = 0, worst_rel = 0;
    for (int i = 0; i <= 255 * 64; ++i) {
        const float code = float(i) / 64.0f;
        const double want = exact_srgb(code), got = curve(code);
        worst_abs = std::max(worst_abs, std::abs(got - want));
        if (want > 0) worst_rel = std::max(worst_rel, std::abs(got - want) / want);
    }
    EXPECT_LT(worst_abs, 1e-7);
    EXPECT_LT(worst_rel, 2e-6);
    // Clamped outside 0..255 (a filtered code never is, but the curve must not extrapolate).
    EXPECT_EQ(curve(-3.0f), 0.0f);
    EXPECT_EQ(curve(300.0f), curve(255.0f));
    EXPECT_NEAR(curve(255.0f), 1.0, 1e-7);
    // Continuous where the linear piece meets the power law.
    EXPECT_NEAR(curve(10.3147f), curve(10.3148f), 1e-7);
}

namespace {
// decode<W> at W lanes against the plain C++ width, bit for bit, over every 1/16 of a code
// (and below 0, above 255, and NaN).
template <int W>
void expect_decode_equals_scalar() {
    const SrgbCurve& curve = srgb_curve();
    alignas(64) float in[16], out[16];
    for (int base = -32; base < 255 * 16 + 64; base += 16) {
        for (int k = 0; k < 16; ++k) in[k] = float(base + k) / 16.0f + 0.013f * float(k);
        if (base == 0) in[3] = std::nanf("");
        for (int k = 0; k < 16; k += W) curve.decode<W>(Lanes<W>::F::load(in + k)).store(out + k);
        for (int k = 0; k < 16; ++k) {
            const float want = curve.decode<1>(Lanes<1>::F(in[k])).v;
            ASSERT_EQ(std::memcmp(&out[k], &want, sizeof want), 0) << "width " << W << " code " << in[k];
        }
    }
}
}  // namespace

TEST(SrgbCurve, EveryWidthEqualsTheScalarDecode) {
#if defined(__AVX2__)
    expect_decode_equals_scalar<8>();
#endif
#if defined(__AVX512F__)
    expect_decode_equals_scalar<16>();
#endif
    // A NaN code decodes to 0 (as the lanes' clamp makes it).
    EXPECT_EQ(srgb_curve()(std::nanf("")), 0.0f);
}
