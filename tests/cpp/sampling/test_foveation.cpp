// The foveated eye's composite against analytic results: bilinear upsampling reproduces a
// linear ramp exactly (away from the clamped edges), weight 1 gives the fovea's pixels as
// traced, weight w the mix, and sizes that do not fit are an InvalidArgument.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "common/error.h"
#include "sampling/foveation.h"

using namespace gigascroll;

namespace {

FoveatedEye eye_of(std::uint32_t w, std::uint32_t h, std::uint32_t k, std::uint32_t fw,
                   std::uint32_t fh) {
    FoveatedEye e;
    e.width = w, e.height = h, e.factor = k;
    e.periphery_width = (w + k - 1) / k, e.periphery_height = (h + k - 1) / k;
    e.fovea_width = fw, e.fovea_height = fh;
    e.x0 = (w - fw) / 2, e.y0 = (h - fh) / 2;
    return e;
}

// Continuous periphery coordinate of eye pixel i (centred, k times coarser).
double coarse_coord(std::uint32_t i, std::uint32_t n_out, std::uint32_t n_in, std::uint32_t k) {
    return (i + 0.5 - n_out / 2.0) / k + n_in / 2.0 - 0.5;
}

}  // namespace

TEST(Foveation, UpsamplingReproducesALinearRamp) {
    for (std::uint32_t k : {2u, 3u, 4u}) {
        const FoveatedEye e = eye_of(61, 50, k, 12, 10);
        std::vector<float> per(std::size_t(e.periphery_width) * e.periphery_height * 3);
        for (std::uint32_t y = 0; y < e.periphery_height; ++y)
            for (std::uint32_t x = 0; x < e.periphery_width; ++x)
                for (int c = 0; c < 3; ++c)
                    per[(std::size_t(y) * e.periphery_width + x) * 3 + c] =
                        float(0.25 * x + 0.5 * y + c);
        std::vector<float> fovea(std::size_t(e.fovea_width) * e.fovea_height * 3, -1.0f);
        std::vector<float> zero_x(e.fovea_width, 0.0f), zero_y(e.fovea_height, 0.0f);
        std::vector<float> out(std::size_t(e.width) * e.height * 3);
        composite_foveated(e, per.data(), fovea.data(), zero_x.data(), zero_y.data(), out.data(), 2);
        int checked = 0;
        for (std::uint32_t y = 0; y < e.height; ++y)
            for (std::uint32_t x = 0; x < e.width; ++x) {
                const double u = coarse_coord(x, e.width, e.periphery_width, k);
                const double v = coarse_coord(y, e.height, e.periphery_height, k);
                if (u < 0 || v < 0 || u > e.periphery_width - 1 || v > e.periphery_height - 1)
                    continue;  // clamped at the edge
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(out[(std::size_t(y) * e.width + x) * 3 + c], 0.25 * u + 0.5 * v + c,
                                1e-4);
                ++checked;
            }
        EXPECT_GT(checked, int(e.width * e.height) / 2);
    }
}

TEST(Foveation, FoveaWeightsBlendOverThePeriphery) {
    const FoveatedEye e = eye_of(40, 44, 2, 16, 12);
    std::vector<float> per(std::size_t(e.periphery_width) * e.periphery_height * 3, 0.25f);
    std::vector<float> fovea(std::size_t(e.fovea_width) * e.fovea_height * 3);
    for (std::size_t i = 0; i < fovea.size(); ++i) fovea[i] = float(i % 97) / 97.0f;
    std::vector<float> wx(e.fovea_width), wy(e.fovea_height);
    for (std::uint32_t i = 0; i < e.fovea_width; ++i) wx[i] = i < 3 ? float(i) / 3 : 1.0f;
    for (std::uint32_t i = 0; i < e.fovea_height; ++i) wy[i] = i == 0 ? 0.5f : 1.0f;
    std::vector<float> out(std::size_t(e.width) * e.height * 3), again(out.size());
    composite_foveated(e, per.data(), fovea.data(), wx.data(), wy.data(), out.data(), 2);
    composite_foveated(e, per.data(), fovea.data(), wx.data(), wy.data(), again.data(), 1);
    EXPECT_EQ(out, again);  // rows are independent: threads do not change a bit
    for (std::uint32_t y = 0; y < e.height; ++y)
        for (std::uint32_t x = 0; x < e.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const float got = out[(std::size_t(y) * e.width + x) * 3 + c];
                const bool inside = x >= e.x0 && x < e.x0 + e.fovea_width && y >= e.y0 &&
                                    y < e.y0 + e.fovea_height;
                if (!inside) {
                    EXPECT_FLOAT_EQ(got, 0.25f);
                    continue;
                }
                const std::uint32_t fx = x - e.x0, fy = y - e.y0;
                const float f = fovea[(std::size_t(fy) * e.fovea_width + fx) * 3 + c];
                const float w = wx[fx] * wy[fy];
                if (w == 1.0f)
                    EXPECT_EQ(got, f);
                else
                    EXPECT_NEAR(got, w * f + (1 - w) * 0.25f, 1e-6);
            }
}

TEST(Foveation, SizesThatDoNotFitAreRefused) {
    std::vector<float> buf(64 * 64 * 3), w(64, 1.0f);
    FoveatedEye e = eye_of(32, 32, 2, 8, 8);
    e.x0 = 30;  // fovea sticks out of the eye
    EXPECT_THROW(composite_foveated(e, buf.data(), buf.data(), w.data(), w.data(), buf.data()),
                 InvalidArgument);
    e = eye_of(32, 32, 2, 8, 8);
    e.periphery_width = 15;  // 15 x 2 < 32: does not cover the eye
    EXPECT_THROW(composite_foveated(e, buf.data(), buf.data(), w.data(), w.data(), buf.data()),
                 InvalidArgument);
    e = eye_of(32, 32, 2, 8, 8);
    e.factor = 0;
    EXPECT_THROW(composite_foveated(e, buf.data(), buf.data(), w.data(), w.data(), buf.data()),
                 InvalidArgument);
}
