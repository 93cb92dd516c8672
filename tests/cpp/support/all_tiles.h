// Every tile of every level of every painting of a pack layout.
#pragma once
#include <cstdint>
#include <vector>

#include "pack/geometry.h"
#include "pack/tile_key.h"

namespace gigascroll {

inline std::vector<TileKey> all_tiles(const PackGeometry& layout) {
    std::vector<TileKey> keys;
    for (std::uint32_t p = 0; p < layout.paintings.size(); ++p) {
        const auto& pt = layout.paintings[p];
        for (std::uint32_t l = 0; l < pt.levels(); ++l)
            for (std::uint32_t y = 0; y < pt.tiles_y(l); ++y)
                for (std::uint32_t x = 0; x < pt.tiles_x(l); ++x) keys.push_back({p, l, x, y});
    }
    return keys;
}

}  // namespace gigascroll
