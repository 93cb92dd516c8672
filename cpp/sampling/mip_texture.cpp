#include "sampling/mip_texture.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"
#include "common/parallel.h"
#include "sampling/bilinear.h"
#include "pack/reader.h"

namespace gigascroll {

MipTexture::MipTexture(std::vector<Level> levels) : levels_(std::move(levels)) {
    require(!levels_.empty() && levels_.size() <= LevelAxes::kMaxLevels, "MipTexture: 1 to 32 levels");
    const std::uint32_t W = levels_[0].width, H = levels_[0].height;
    for (std::uint32_t l = 0; l < levels_.size(); ++l) {
        const Level& lv = levels_[l];
        require(lv.width == ((W + (1u << l) - 1) >> l) && lv.height == ((H + (1u << l) - 1) >> l) &&
                    lv.rgb.size() == std::size_t(lv.width) * lv.height * 3,
                "MipTexture: level " + std::to_string(l) + " has the wrong size");
    }
}

MipTexture MipTexture::from_pack(const TilePack& pack, std::uint32_t painting, std::uint32_t count) {
    require(painting < pack.paintings().size(), "painting out of range");
    const PaintingGeometry& g = pack.paintings()[painting].geometry;
    if (count == 0 || count > g.levels()) count = g.levels();
    const std::size_t T = pack.tile_size(), E = pack.border(), P = pack.payload();
    std::vector<std::uint8_t> tile(pack.tile_bytes());
    std::vector<Level> levels(count);
    for (std::uint32_t l = 0; l < count; ++l) {
        const LevelGeometry& lg = g.level(l);
        Level& lv = levels[l];
        lv.width = lg.width;
        lv.height = lg.height;
        lv.rgb.resize(std::size_t(lv.width) * lv.height * 3);
        for (std::uint32_t ty = 0; ty < lg.tiles_y; ++ty)
            for (std::uint32_t tx = 0; tx < lg.tiles_x; ++tx) {
                pack.read_tile(painting, l, tx, ty, tile.data());
                const std::size_t w = std::min<std::size_t>(P, lv.width - tx * P);
                const std::size_t h = std::min<std::size_t>(P, lv.height - ty * P);
                for (std::size_t y = 0; y < h; ++y)
                    std::copy_n(tile.data() + ((E + y) * T + E) * 3, w * 3,
                                lv.rgb.data() + ((ty * P + y) * lv.width + tx * P) * 3);
            }
    }
    return MipTexture(std::move(levels));
}

void MipTexture::sample(const SampleRequest& r) const {
    require(r.u && r.v && r.out, "sample: missing arrays");
    require(r.uv_stride >= 1, "sample: uv_stride must be >= 1");
    const std::uint32_t L = level_count();
    const double W = levels_[0].width, H = levels_[0].height;
    const LevelAxes axes(levels_[0].width, levels_[0].height, L);
    auto bilinear = [&](double x0, double y0, std::uint32_t l, float* out) {
        const Level& lv = levels_[l];
        const Tap tx = axes.tap_x(x0, l), ty = axes.tap_y(y0, l);
        const std::size_t row = std::size_t(lv.width) * 3;
        const std::uint8_t* p00 = lv.rgb.data() + std::size_t(ty.i0) * row + std::size_t(tx.i0) * 3;
        bilerp_rgb8(p00, row, tx.i0 + 1 < lv.width ? 3 : 0, ty.i0 + 1 < lv.height ? 1 : 0, tx.f, ty.f, out);
    };
    parallel_for(r.count, 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            const double ui = r.u[i * r.uv_stride], vi = r.v[i * r.uv_stride];
            const double u = std::isnan(ui) ? 0.0 : std::clamp(ui, 0.0, 1.0);
            const double v = std::isnan(vi) ? 0.0 : std::clamp(vi, 0.0, 1.0);
            const double x0 = u * W, y0 = v * H;
            float lod = r.lod ? r.lod[i] : r.lod_scalar;
            lod = std::isnan(lod) ? 0.0f : std::clamp(lod, 0.0f, float(L - 1));
            float* out = r.out + 3 * i;
            std::uint32_t l0;
            if (r.filter == Filter::Bilinear) {
                l0 = static_cast<std::uint32_t>(std::lround(lod));
                bilinear(x0, y0, l0, out);
            } else {
                l0 = static_cast<std::uint32_t>(lod);
                const float f = lod - float(l0);
                bilinear(x0, y0, l0, out);
                if (f > 0 && l0 + 1 < L) {
                    float c[3];
                    bilinear(x0, y0, l0 + 1, c);
                    for (int k = 0; k < 3; ++k) out[k] += f * (c[k] - out[k]);
                }
            }
            if (r.level_out) r.level_out[i] = static_cast<std::int8_t>(l0);
        }
    }, r.threads);
}

}  // namespace gigascroll
