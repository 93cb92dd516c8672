#include "vt/tile_geometry.h"

#include <bit>
#include <string>

#include "common/error.h"

namespace gigascroll {

namespace {
std::uint32_t ceil_div(std::uint64_t a, std::uint64_t b) {
    return static_cast<std::uint32_t>((a + b - 1) / b);
}
}  // namespace

PaintingTiles::PaintingTiles(std::uint32_t width, std::uint32_t height, std::uint32_t tile_size,
                             std::uint32_t border)
    : width_(width), height_(height), tile_size_(tile_size), border_(border) {
    require(width > 0 && height > 0, "painting size must be positive, got " +
                                         std::to_string(width) + " x " + std::to_string(height));
    require(tile_size > 2 * border, "tile_size must exceed 2 * border");
    require(tile_size <= 65536, "tile_size too large");
    const std::uint32_t p = payload();
    level_offset_.push_back(0);
    for (std::uint32_t l = 0;; ++l) {
        const std::uint32_t tx = ceil_div(level_width(l), p), ty = ceil_div(level_height(l), p);
        // Request keys hold tile coordinates in 16 bits each (see request.h).
        require(tx <= 65536 && ty <= 65536, "painting too large: more than 65536 tiles per axis");
        tiles_x_.push_back(tx);
        tiles_y_.push_back(ty);
        level_offset_.push_back(level_offset_.back() + std::uint64_t(tx) * ty);
        if (tx == 1 && ty == 1) break;
    }
}

std::uint32_t PaintingTiles::level_width(std::uint32_t level) const {
    return level >= 32 ? 1 : ceil_div(width_, std::uint64_t(1) << level);
}
std::uint32_t PaintingTiles::level_height(std::uint32_t level) const {
    return level >= 32 ? 1 : ceil_div(height_, std::uint64_t(1) << level);
}
std::uint32_t PaintingTiles::page_table_width() const { return std::bit_ceil(tiles_x_[0]); }
std::uint32_t PaintingTiles::page_table_height() const { return std::bit_ceil(tiles_y_[0]); }

}  // namespace gigascroll
