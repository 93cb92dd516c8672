// What the virtual-texture samplers share once a sample's tile is known (VT-mobile-VR eqs
// 7-10): the page-table entry of a tile and a texel's address in the slot that answers it,
// and the extents the batched and the 16-lane samplers take their taps in.
#pragma once
#include <algorithm>
#include <cstddef>
#include <cstdint>

#include "cache/virtual_texture.h"

namespace gigascroll {

// What both sampling paths do once a sample's tile is known: its page-table entry (looked up
// again only when a sample leaves the last tile; neighbours mostly share it) and the
// physical address of a texel of the tile that answered.
class TexelFinder {
public:
    TexelFinder(const VirtualTexture& vt, std::uint32_t painting)
        : table_(vt.page_table()), painting_(painting), physical_(vt.physical()),
          P_(table_.layout().payload()), E_(table_.layout().border), T_(table_.layout().tile_size),
          tile_bytes_(vt.slot_bytes()) {}

    std::size_t row_bytes() const { return std::size_t(T_) * 3; }

    // Forgets the last entry (the next lookup reads the table: its residency may be new).
    void forget() { last_l_ = ~0u; }

    // Entry of tile (cx, cy) at level l: the level and slot of its finest resident ancestor.
    PageEntry entry(std::uint32_t l, std::uint32_t cx, std::uint32_t cy) {
        if (l != last_l_ || cx != last_cx_ || cy != last_cy_)
            last_l_ = l, last_cx_ = cx, last_cy_ = cy, last_ = table_.lookup(painting_, l, cx, cy);
        return last_;
    }

    // Texel (i, j) of e's level, where e answers tile (cx, cy) from s levels coarser:
    // eq (7,8)'s in-tile offset with the border, clamped so the 2 x 2 footprint stays inside.
    const std::uint8_t* texel(PageEntry e, std::uint32_t s, std::int64_t i, std::int64_t j,
                              std::uint32_t cx, std::uint32_t cy) const {
        std::uint32_t jx, jy;
        const std::uint8_t* tile = footprint(e, s, i, j, cx, cy, jx, jy);
        return tile + jy * row_bytes() + jx * 3;
    }

    // The same for any slot format: the slot's first byte and the in-tile texel (jx, jy).
    const std::uint8_t* footprint(PageEntry e, std::uint32_t s, std::int64_t i, std::int64_t j,
                                  std::uint32_t cx, std::uint32_t cy, std::uint32_t& jx,
                                  std::uint32_t& jy) const {
        jx = std::uint32_t(std::clamp<std::int64_t>(i - std::int64_t(cx >> s) * P_ + E_, 0, T_ - 2));
        jy = std::uint32_t(std::clamp<std::int64_t>(j - std::int64_t(cy >> s) * P_ + E_, 0, T_ - 2));
        return physical_ + std::size_t(e.slot()) * tile_bytes_;
    }

private:
    const PageTable& table_;
    const std::uint32_t painting_;
    const std::uint8_t* const physical_;
    const std::int64_t P_, E_, T_;
    const std::size_t tile_bytes_;
    std::uint32_t last_l_ = ~0u, last_cx_ = 0, last_cy_ = 0;
    PageEntry last_;
};

// A painting's level-0 size and coarsest level.
struct PyramidExtent {
    std::uint32_t width, height;  // level 0, texels
    float top;                    // the coarsest level
};

// The slots' layout: payload and border texels a tile side, texels a slot side, bytes a row.
struct TileExtent {
    std::int32_t payload, border, tile, row_bytes;
};

}  // namespace gigascroll
