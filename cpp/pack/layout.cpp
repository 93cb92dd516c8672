#include "pack/layout.h"

#include <algorithm>
#include <bit>
#include <string>

#include "common/bits.h"
#include "common/error.h"
#include "pack/reader.h"

namespace gigascroll {

std::uint32_t VtPainting::merged_levels() const {
    const std::uint32_t fit = std::countr_zero(std::min(table_w, table_h)) + 1;
    return std::min(fit, level_count());
}

VtLayout VtLayout::make(std::uint32_t tile_size, std::uint32_t border,
                        const std::vector<std::pair<std::uint32_t, std::uint32_t>>& sizes) {
    require(tile_size > 2 * border && border >= 1, "tile_size must exceed 2 * border, border >= 1");
    VtLayout layout;
    layout.tile_size = tile_size;
    layout.border = border;
    const std::uint32_t P = layout.payload();
    std::uint32_t x = 0, h = 1;
    for (auto [w, hgt] : sizes) {
        require(w > 0 && hgt > 0, "painting sizes must be positive");
        VtPainting p;
        p.width = w;
        p.height = hgt;
        for (std::uint32_t l = 0;; ++l) {
            const std::uint32_t lw = (w + (1u << l) - 1) >> l, lh = (hgt + (1u << l) - 1) >> l;
            p.tiles_x.push_back((lw + P - 1) / P);
            p.tiles_y.push_back((lh + P - 1) / P);
            if (lw <= P && lh <= P) break;
        }
        p.table_w = next_pow2(p.tiles_x[0]);
        p.table_h = next_pow2(p.tiles_y[0]);
        x = (x + p.table_w - 1) / p.table_w * p.table_w;  // aligned to its own size
        p.table_x = x;
        p.table_y = 0;
        x += p.table_w;
        h = std::max(h, p.table_h);
        layout.paintings.push_back(std::move(p));
    }
    layout.table_w = next_pow2(std::max(x, 1u));
    layout.table_h = next_pow2(h);
    return layout;
}

VtLayout VtLayout::from_pack(const TilePack& pack) {
    VtLayout layout;
    layout.tile_size = pack.tile_size();
    layout.border = pack.border();
    layout.table_w = pack.table_width();
    layout.table_h = pack.table_height();
    for (const PaintingInfo& info : pack.paintings()) {
        VtPainting p;
        p.width = info.width();
        p.height = info.height();
        p.table_w = info.geometry.table_width;
        p.table_h = info.geometry.table_height;
        p.table_x = info.table_x;
        p.table_y = info.table_y;
        for (const LevelGeometry& lv : info.geometry.levels) {
            p.tiles_x.push_back(lv.tiles_x);
            p.tiles_y.push_back(lv.tiles_y);
        }
        layout.paintings.push_back(std::move(p));
    }
    layout.validate();
    return layout;
}

void VtLayout::validate() const {
    require(tile_size > 2 * border && border >= 1, "layout: tile_size must exceed 2 * border, border >= 1");
    require(!paintings.empty(), "layout: no paintings");
    for (std::size_t i = 0; i < paintings.size(); ++i) {
        const VtPainting& p = paintings[i];
        const std::string who = "layout: painting " + std::to_string(i);
        require(p.level_count() > 0 && p.tiles_y.size() == p.tiles_x.size(), who + " has no levels");
        require(p.level_count() <= 32, who + " has more than 32 levels");
        require(is_pow2(p.table_w) && is_pow2(p.table_h),
                who + ": page table size is not a power of two");
        require(p.table_w >= p.tiles_x[0] && p.table_h >= p.tiles_y[0], who + ": page table too small");
        require(p.table_x % p.table_w == 0 && p.table_y % p.table_h == 0, who + ": offset not aligned");
        require(p.table_x + p.table_w <= table_w && p.table_y + p.table_h <= table_h,
                who + ": outside the merged table");
        require(p.tiles_x.back() <= (1u << 20) && p.tiles_x[0] < (1u << 20) && p.tiles_y[0] < (1u << 20),
                who + ": too many tiles");
    }
}

}  // namespace gigascroll
