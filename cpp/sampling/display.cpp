#include "sampling/display.h"

#include <algorithm>

#include "common/error.h"
#include "common/parallel.h"
#include "pack/tile_key.h"

namespace gigascroll {

void display_view(const VirtualTexture& vt, const std::uint64_t* keys, const float* lod,
                  const double* uv, std::uint32_t width, std::uint32_t height,
                  std::uint32_t step, float* out, unsigned threads) {
    require(step >= 1, "display step must be >= 1");
    require(keys && lod && uv && out, "display_view: missing arrays");
    const std::uint32_t ow = display_extent(width, step), oh = display_extent(height, step);
    const std::size_t paintings = vt.layout().paintings.size();
    parallel_for(oh, 8, [&](std::size_t row_begin, std::size_t row_end) {
        for (std::size_t oy = row_begin; oy < row_end; ++oy) {
            const std::uint64_t* key_row = keys + oy * step * std::size_t(width);
            const std::size_t first = oy * ow;  // the row's first sample on the display grid
            float* out_row = out + first * 3;
            // Runs of samples that see the same painting are sampled in one call, straight
            // from the interleaved uv.
            for (std::uint32_t j0 = 0; j0 < ow;) {
                auto painting_at = [&](std::uint32_t j) {
                    const std::uint64_t k = key_row[std::size_t(j) * step];
                    return k == kNoRequest ? ~0u : request_painting(k);
                };
                const std::uint32_t p = painting_at(j0);
                std::uint32_t j1 = j0 + 1;
                while (j1 < ow && painting_at(j1) == p) ++j1;
                if (p == ~0u) {
                    std::fill(out_row + 3 * j0, out_row + 3 * j1, 0.0f);
                } else {
                    require(p < paintings, "display_view: a key names a painting the virtual "
                                           "texture does not hold");
                    SampleRequest r;
                    r.painting = p;
                    r.u = uv + 2 * (first + j0), r.v = r.u + 1, r.uv_stride = 2;
                    r.lod = lod + first + j0;
                    r.count = j1 - j0;
                    r.filter = Filter::Bilinear;
                    r.out = out_row + 3 * j0;
                    sample_serial(vt, r);
                }
                j0 = j1;
            }
        }
    }, threads);
}

}  // namespace gigascroll
