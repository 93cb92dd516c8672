#include "pack/geometry.h"

#include <string>

#include "common/bits.h"
#include "common/error.h"

namespace gigascroll {

void check_tile_parameters(std::uint32_t tile_size, std::uint32_t border) {
    require(tile_size >= 2 && tile_size <= 4096,
            "tile_size must be in [2, 4096], got " + std::to_string(tile_size));
    require(tile_size > 2 * border, "tile_size (" + std::to_string(tile_size) +
                                        ") must be larger than 2 * border (" +
                                        std::to_string(2 * border) + ")");
}

PaintingGeometry make_geometry(std::uint32_t width, std::uint32_t height, std::uint32_t tile_size,
                               std::uint32_t border) {
    check_tile_parameters(tile_size, border);
    require(width > 0 && height > 0, "image is empty (" + std::to_string(width) + " x " +
                                         std::to_string(height) + ")");
    require(width <= (1u << 30) && height <= (1u << 30), "image is too large");
    PaintingGeometry g;
    g.width = width;
    g.height = height;
    g.tile_size = tile_size;
    g.border = border;
    g.payload = tile_size - 2 * border;
    const std::uint32_t P = g.payload;
    for (std::uint32_t l = 0;; ++l) {
        LevelGeometry lv;
        lv.width = static_cast<std::uint32_t>((std::uint64_t(width) + (1ull << l) - 1) >> l);
        lv.height = static_cast<std::uint32_t>((std::uint64_t(height) + (1ull << l) - 1) >> l);
        lv.tiles_x = (lv.width + P - 1) / P;
        lv.tiles_y = (lv.height + P - 1) / P;
        lv.first_entry = g.tile_count;
        g.tile_count += std::uint64_t(lv.tiles_x) * lv.tiles_y;
        g.levels.push_back(lv);
        if (lv.width <= P && lv.height <= P) break;
    }
    g.table_width = next_pow2(g.levels[0].tiles_x);
    g.table_height = next_pow2(g.levels[0].tiles_y);
    return g;
}

}  // namespace gigascroll
