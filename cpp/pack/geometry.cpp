#include "pack/geometry.h"

#include <algorithm>
#include <bit>
#include <string>

#include "common/bits.h"
#include "common/error.h"

namespace gigascroll {

void check_tile_parameters(std::uint32_t tile_size, std::uint32_t border) {
    require(tile_size >= 2 && tile_size <= 4096,
            "tile_size must be in [2, 4096], got " + std::to_string(tile_size));
    // 64-bit: a border of 2^31 must not wrap 2 * border to 0.
    require(std::uint64_t(tile_size) > 2 * std::uint64_t(border),
            "tile_size (" + std::to_string(tile_size) + ") must be larger than 2 * border (" +
                std::to_string(2 * std::uint64_t(border)) + ")");
}

PaintingGeometry::PaintingGeometry(std::uint32_t width, std::uint32_t height,
                                   std::uint32_t tile_size, std::uint32_t border)
    : width_(width), height_(height), tile_size_(tile_size), border_(border) {
    check_tile_parameters(tile_size, border);
    require(width > 0 && height > 0, "image is empty (" + std::to_string(width) + " x " +
                                         std::to_string(height) + ")");
    require(width <= (1u << 30) && height <= (1u << 30), "image is too large");
    payload_ = tile_size - 2 * border;
    const std::uint32_t P = payload_;
    for (std::uint32_t l = 0;; ++l) {
        LevelGeometry lv;
        lv.width = static_cast<std::uint32_t>((std::uint64_t(width) + (1ull << l) - 1) >> l);
        lv.height = static_cast<std::uint32_t>((std::uint64_t(height) + (1ull << l) - 1) >> l);
        lv.tiles_x = (lv.width + P - 1) / P;
        lv.tiles_y = (lv.height + P - 1) / P;
        lv.first_tile = total_tiles_;
        total_tiles_ += std::uint64_t(lv.tiles_x) * lv.tiles_y;
        levels_.push_back(lv);
        if (lv.width <= P && lv.height <= P) break;
    }
    table_width_ = next_pow2(levels_[0].tiles_x);
    table_height_ = next_pow2(levels_[0].tiles_y);
}

std::uint32_t PaintingGeometry::merged_levels() const {
    const std::uint32_t fit = std::countr_zero(std::min(table_width_, table_height_)) + 1;
    return std::min(fit, levels());
}

PackGeometry PackGeometry::make(std::uint32_t tile_size, std::uint32_t border,
                                const std::vector<std::pair<std::uint32_t, std::uint32_t>>& sizes) {
    require(tile_size > 2 * border && border >= 1, "tile_size must exceed 2 * border, border >= 1");
    PackGeometry pack;
    pack.tile_size = tile_size;
    pack.border = border;
    std::uint32_t x = 0, h = 1;
    std::uint64_t entries = 0;
    for (auto [w, hgt] : sizes) {
        require(w > 0 && hgt > 0, "painting sizes must be positive");
        PaintingGeometry p(w, hgt, tile_size, border);
        x = (x + p.page_table_width() - 1) / p.page_table_width() * p.page_table_width();
        p.place(x, 0, entries);
        x += p.page_table_width();
        h = std::max(h, p.page_table_height());
        entries += p.total_tiles();
        pack.paintings.push_back(std::move(p));
    }
    pack.table_width = next_pow2(std::max(x, 1u));
    pack.table_height = next_pow2(h);
    return pack;
}

void PackGeometry::validate() const {
    require(tile_size > 2 * border && border >= 1, "layout: tile_size must exceed 2 * border, border >= 1");
    require(!paintings.empty(), "layout: no paintings");
    for (std::size_t i = 0; i < paintings.size(); ++i) {
        const PaintingGeometry& p = paintings[i];
        const std::string who = "layout: painting " + std::to_string(i);
        require(p.levels() > 0, who + " has no levels");
        require(p.levels() <= 32, who + " has more than 32 levels");
        require(p.tile_size() == tile_size && p.border() == border,
                who + ": tile size or border differs from the pack's");
        require(is_pow2(p.page_table_width()) && is_pow2(p.page_table_height()),
                who + ": page table size is not a power of two");
        require(p.page_table_width() >= p.tiles_x(0) && p.page_table_height() >= p.tiles_y(0),
                who + ": page table too small");
        require(p.table_x() % p.page_table_width() == 0 && p.table_y() % p.page_table_height() == 0,
                who + ": offset not aligned");
        require(std::uint64_t(p.table_x()) + p.page_table_width() <= table_width &&
                    std::uint64_t(p.table_y()) + p.page_table_height() <= table_height,
                who + ": outside the merged table");
        require(p.tiles_x(0) < (1u << 20) && p.tiles_y(0) < (1u << 20), who + ": too many tiles");
    }
}

}  // namespace gigascroll
