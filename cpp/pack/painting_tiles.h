// Tile geometry of one painting as the views see it: mip levels, tiles per level, flat tile
// indices. The levels and tile grids are the pack's own (make_geometry in pack_geometry.h is
// the single source of truth); this class adds the flat per-painting tile index used by the
// flag array and checks that tile coordinates fit the 16 bits of a request key.
#pragma once
#include <cstdint>

#include "pack/geometry.h"

namespace gigascroll {

class PaintingTiles {
public:
    PaintingTiles(std::uint32_t width, std::uint32_t height, std::uint32_t tile_size = 128,
                  std::uint32_t border = 4);

    const PaintingGeometry& geometry() const { return g_; }
    std::uint32_t width() const { return g_.width; }
    std::uint32_t height() const { return g_.height; }
    std::uint32_t tile_size() const { return g_.tile_size; }
    std::uint32_t border() const { return g_.border; }
    std::uint32_t payload() const { return g_.payload; }
    std::uint32_t levels() const { return g_.level_count(); }

    std::uint32_t level_width(std::uint32_t level) const;
    std::uint32_t level_height(std::uint32_t level) const;
    std::uint32_t tiles_x(std::uint32_t level) const { return g_.levels.at(level).tiles_x; }
    std::uint32_t tiles_y(std::uint32_t level) const { return g_.levels.at(level).tiles_y; }
    std::uint64_t tile_count(std::uint32_t level) const {
        return std::uint64_t(tiles_x(level)) * tiles_y(level);
    }
    // Tiles of all levels together, and the first flat index of a level (levels 0..l-1 first,
    // row-major inside a level: seed 002's page index).
    std::uint64_t total_tiles() const { return g_.tile_count; }
    std::uint64_t level_offset(std::uint32_t level) const {
        return level == levels() ? g_.tile_count : g_.levels.at(level).first_entry;
    }

    // Level-0 page table size: the next powers of two of the level-0 tile counts (eqs 3, 4).
    std::uint32_t page_table_width() const { return g_.table_width; }
    std::uint32_t page_table_height() const { return g_.table_height; }

private:
    PaintingGeometry g_;
};

}  // namespace gigascroll
