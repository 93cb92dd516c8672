// Tile geometry of one painting: mip levels, tiles per level, flat tile indices.
// Mirrors the pack layout (payload P = tile_size - 2 * border; level l is
// ceil(W / 2^l) x ceil(H / 2^l) texels cut into ceil(W_l / P) x ceil(H_l / P) tiles;
// levels stop at the first one that fits in a single tile).
#pragma once
#include <cstdint>
#include <vector>

namespace gigascroll {

class PaintingTiles {
public:
    PaintingTiles(std::uint32_t width, std::uint32_t height, std::uint32_t tile_size = 128,
                  std::uint32_t border = 4);

    std::uint32_t width() const { return width_; }
    std::uint32_t height() const { return height_; }
    std::uint32_t tile_size() const { return tile_size_; }
    std::uint32_t border() const { return border_; }
    std::uint32_t payload() const { return tile_size_ - 2 * border_; }
    std::uint32_t levels() const { return static_cast<std::uint32_t>(tiles_x_.size()); }

    std::uint32_t level_width(std::uint32_t level) const;
    std::uint32_t level_height(std::uint32_t level) const;
    std::uint32_t tiles_x(std::uint32_t level) const { return tiles_x_.at(level); }
    std::uint32_t tiles_y(std::uint32_t level) const { return tiles_y_.at(level); }
    std::uint64_t tile_count(std::uint32_t level) const {
        return std::uint64_t(tiles_x(level)) * tiles_y(level);
    }
    // Tiles of all levels together, and the first flat index of a level (levels 0..l-1 first,
    // row-major inside a level: seed 002's page index).
    std::uint64_t total_tiles() const { return level_offset_.back(); }
    std::uint64_t level_offset(std::uint32_t level) const { return level_offset_.at(level); }

    // Level-0 page table size: the next powers of two of the level-0 tile counts (eqs 3, 4).
    std::uint32_t page_table_width() const;
    std::uint32_t page_table_height() const;

private:
    std::uint32_t width_, height_, tile_size_, border_;
    std::vector<std::uint32_t> tiles_x_, tiles_y_;
    std::vector<std::uint64_t> level_offset_;  // levels() + 1 entries
};

}  // namespace gigascroll
