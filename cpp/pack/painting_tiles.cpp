#include "pack/painting_tiles.h"

#include <string>

#include "common/error.h"

namespace gigascroll {

PaintingTiles::PaintingTiles(std::uint32_t width, std::uint32_t height, std::uint32_t tile_size,
                             std::uint32_t border)
    : g_(make_geometry(width, height, tile_size, border)) {
    // Request keys hold tile coordinates in 16 bits each (see request.h).
    require(g_.levels[0].tiles_x <= 65536 && g_.levels[0].tiles_y <= 65536,
            "painting too large: more than 65536 tiles per axis");
}

std::uint32_t PaintingTiles::level_width(std::uint32_t level) const {
    return g_.levels.at(level).width;
}
std::uint32_t PaintingTiles::level_height(std::uint32_t level) const {
    return g_.levels.at(level).height;
}

}  // namespace gigascroll
