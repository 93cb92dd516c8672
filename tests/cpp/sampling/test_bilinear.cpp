// The bilinear blends of one pixel's channels in SSE's four lanes (and AVX2's eight, two
// footprints) against their plain C++ twins, bit for bit, on random texels and weights
// (weights 0 and 1 among them).
#include <gtest/gtest.h>

#include <bit>
#include <cstdint>
#include <random>
#include <vector>

#include "sampling/bilinear.h"

using namespace gigascroll;

namespace {
bool same(float a, float b) { return std::bit_cast<std::uint32_t>(a) == std::bit_cast<std::uint32_t>(b); }
}  // namespace

TEST(Bilinear, LaneBlendsEqualTheirScalarTwins) {
    std::mt19937 rng(17);
    std::uniform_int_distribution<int> byte(0, 255);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    constexpr std::size_t kStride = 3 * 9;
    std::vector<std::uint8_t> fine(2 * kStride + 8), coarse(2 * kStride + 8);
    for (int trial = 0; trial < 5000; ++trial) {
        for (auto& b : fine) b = std::uint8_t(byte(rng));
        for (auto& b : coarse) b = std::uint8_t(byte(rng));
        const float fx0 = trial % 17 == 0 ? 0.0f : unit(rng), fy0 = trial % 19 == 0 ? 1.0f : unit(rng);
        const float fx1 = unit(rng), fy1 = unit(rng), blend = trial % 5 == 0 ? 0.0f : unit(rng);
        const std::size_t at = 3 * std::size_t(trial % 6);  // a texel of the first row
        float want[3], got[4];
#if defined(__SSE2__)
        bilerp_rgb8(fine.data() + at, kStride, 3, 1, fx0, fy0, want);
        bilerp_rgb8_wide(fine.data() + at, kStride, fx0, fy0, got);
        for (int c = 0; c < 3; ++c) ASSERT_TRUE(same(got[c], want[c])) << "bilerp_rgb8_wide trial " << trial;
#endif
        blend_levels_rgb8_scalar(fine.data() + at, coarse.data() + at, kStride, fx0, fy0, fx1, fy1, blend, want);
        for (bool wide : {false, true}) {
            blend_levels_rgb8(fine.data() + at, coarse.data() + at, kStride, fx0, fy0, fx1, fy1, blend, wide, got);
            for (int c = 0; c < 3; ++c) ASSERT_TRUE(same(got[c], want[c])) << "blend_levels_rgb8 trial " << trial;
        }
        // The scalar twin against its definition: f + blend (g - f) of the two bilinear blends.
        float f[3], g[3];
        bilerp_rgb8(fine.data() + at, kStride, 3, 1, fx0, fy0, f);
        bilerp_rgb8(coarse.data() + at, kStride, 3, 1, fx1, fy1, g);
        for (int c = 0; c < 3; ++c) ASSERT_NEAR(want[c], f[c] + blend * (g[c] - f[c]), 1e-3f);
        // Words: the texels as r | g << 8 | b << 16.
        std::uint32_t words[4];
        const std::size_t corner[4] = {at, at + 3, at + kStride, at + kStride + 3};
        for (int k = 0; k < 4; ++k)
            words[k] = std::uint32_t(fine[corner[k]]) | std::uint32_t(fine[corner[k] + 1]) << 8 |
                       std::uint32_t(fine[corner[k] + 2]) << 16;
        bilerp_words_scalar(words, fx0, fy0, want);
        bilerp_words(words, fx0, fy0, got);
        for (int c = 0; c < 3; ++c) ASSERT_TRUE(same(got[c], want[c])) << "bilerp_words trial " << trial;
        bilerp_rgb8(fine.data() + at, kStride, 3, 1, fx0, fy0, f);
        for (int c = 0; c < 3; ++c) ASSERT_TRUE(same(want[c], f[c])) << "bilerp_words_scalar trial " << trial;
    }
}
