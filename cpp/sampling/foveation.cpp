#include "sampling/foveation.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <vector>

#include "common/error.h"
#include "common/parallel.h"

namespace gigascroll {
namespace {

struct AxisTap {
    std::uint32_t a, b;  // the two periphery pixels (clamped to the edge)
    float f;             // weight of b
};

// Output pixel i of n_out, centred on an input of n_in pixels `factor` times coarser.
std::vector<AxisTap> axis_taps(std::uint32_t n_out, std::uint32_t n_in, std::uint32_t factor) {
    std::vector<AxisTap> taps(n_out);
    const auto last = static_cast<std::int64_t>(n_in) - 1;
    for (std::uint32_t i = 0; i < n_out; ++i) {
        const double u = (double(i) + 0.5 - double(n_out) / 2) / double(factor) +
                         double(n_in) / 2 - 0.5;
        const double fl = std::floor(u);
        const auto i0 = static_cast<std::int64_t>(fl);
        taps[i] = {static_cast<std::uint32_t>(std::clamp<std::int64_t>(i0, 0, last)),
                   static_cast<std::uint32_t>(std::clamp<std::int64_t>(i0 + 1, 0, last)),
                   static_cast<float>(u - fl)};
    }
    return taps;
}

}  // namespace

void composite_foveated(const FoveatedEye& e, const float* periphery, const float* fovea,
                        const float* weight_x, const float* weight_y, float* out,
                        unsigned threads) {
    require(e.width > 0 && e.height > 0, "foveated eye: empty eye");
    require(e.factor >= 1 && e.factor <= 64, "foveated eye: factor must be in [1, 64]");
    require(std::uint64_t(e.periphery_width) * e.factor >= e.width &&
                std::uint64_t(e.periphery_height) * e.factor >= e.height,
            "foveated eye: the periphery does not cover the eye");
    require(std::uint64_t(e.x0) + e.fovea_width <= e.width &&
                std::uint64_t(e.y0) + e.fovea_height <= e.height,
            "foveated eye: the fovea lies outside the eye");
    const std::vector<AxisTap> tx = axis_taps(e.width, e.periphery_width, e.factor);
    const std::vector<AxisTap> ty = axis_taps(e.height, e.periphery_height, e.factor);
    const std::size_t pw = e.periphery_width;
    parallel_for(e.height, 16, [&](std::size_t y_begin, std::size_t y_end) {
        for (std::size_t y = y_begin; y < y_end; ++y) {
            const AxisTap t = ty[y];
            const float* ra = periphery + std::size_t(t.a) * pw * 3;
            const float* rb = periphery + std::size_t(t.b) * pw * 3;
            const float fy = t.f, gy = 1 - t.f;
            const bool in_rows = y >= e.y0 && y < std::size_t(e.y0) + e.fovea_height;
            const float wy = in_rows ? weight_y[y - e.y0] : 0.0f;
            float* o = out + y * e.width * 3;
            for (std::uint32_t x = 0; x < e.width; ++x) {
                const AxisTap s = tx[x];
                const float fx = s.f, gx = 1 - s.f;
                for (int c = 0; c < 3; ++c) {
                    // rows first (as the numpy reference), then columns
                    const float r0 = ra[s.a * 3 + c] * gy + rb[s.a * 3 + c] * fy;
                    const float r1 = ra[s.b * 3 + c] * gy + rb[s.b * 3 + c] * fy;
                    o[x * 3 + c] = r0 * gx + r1 * fx;
                }
            }
            if (!in_rows) continue;
            const float* fr = fovea + (y - e.y0) * std::size_t(e.fovea_width) * 3;
            float* ob = o + std::size_t(e.x0) * 3;
            for (std::uint32_t x = 0; x < e.fovea_width; ++x) {
                const float w = wy * weight_x[x];
                for (int c = 0; c < 3; ++c)
                    ob[x * 3 + c] = fr[x * 3 + c] * w + ob[x * 3 + c] * (1 - w);
            }
        }
    }, threads);
}

}  // namespace gigascroll
