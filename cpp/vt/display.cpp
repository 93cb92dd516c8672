#include "vt/display.h"

#include <algorithm>
#include <vector>

#include "common/error.h"
#include "common/parallel.h"
#include "vt/request.h"

namespace gigascroll {

void display_view(const VirtualTexture& vt, const std::uint64_t* keys, const float* lod,
                  const double* uv, std::uint32_t width, std::uint32_t height,
                  std::uint32_t step, float* out, unsigned threads) {
    require(step >= 1, "display step must be >= 1");
    require(keys && lod && uv && out, "display_view: missing arrays");
    const std::uint32_t ow = display_extent(width, step), oh = display_extent(height, step);
    const std::size_t paintings = vt.layout().paintings.size();
    parallel_for(oh, 8, [&](std::size_t row_begin, std::size_t row_end) {
        // One row's samples of one painting are gathered contiguous and sampled in one call.
        std::vector<double> u(ow), v(ow);
        std::vector<float> l(ow);
        for (std::size_t oy = row_begin; oy < row_end; ++oy) {
            const std::size_t row = oy * step * std::size_t(width);
            float* out_row = out + oy * ow * 3;
            for (std::uint32_t j0 = 0; j0 < ow;) {
                const std::uint64_t k0 = keys[row + std::size_t(j0) * step];
                const std::uint32_t p = k0 == kNoRequest ? ~0u : request_painting(k0);
                std::uint32_t j1 = j0;
                for (; j1 < ow; ++j1) {
                    const std::uint64_t k = keys[row + std::size_t(j1) * step];
                    if ((k == kNoRequest ? ~0u : request_painting(k)) != p) break;
                    const std::size_t i = oy * ow + j1;  // on the display grid
                    u[j1 - j0] = uv[2 * i], v[j1 - j0] = uv[2 * i + 1], l[j1 - j0] = lod[i];
                }
                if (p == ~0u) {
                    std::fill(out_row + 3 * j0, out_row + 3 * j1, 0.0f);
                } else {
                    require(p < paintings, "display_view: a key names a painting the virtual "
                                           "texture does not hold");
                    SampleRequest r;
                    r.painting = p;
                    r.u = u.data(), r.v = v.data(), r.lod = l.data();
                    r.count = j1 - j0;
                    r.filter = Filter::Bilinear;
                    r.out = out_row + 3 * j0;
                    vt.sample_serial(r);
                }
                j0 = j1;
            }
        }
    }, threads);
}

}  // namespace gigascroll
