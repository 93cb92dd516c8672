// What the runtime needs to know about the paintings of a pack: sizes, tile grids per level
// and where each painting's page table sits in the merged table. Filled from a TilePack
// (from_pack) or directly by tests.
#pragma once
#include <cstdint>
#include <vector>

#include "pack/tile_key.h"

namespace gigascroll {

class TilePack;

struct VtPainting {
    std::uint32_t width = 0, height = 0;        // level-0 texels
    std::uint32_t table_w = 0, table_h = 0;      // Mp x Np, powers of two
    std::uint32_t table_x = 0, table_y = 0;      // offset in the merged table (multiples of Mp, Np)
    std::vector<std::uint32_t> tiles_x, tiles_y; // real tile grid of each level
    std::uint32_t level_count() const { return static_cast<std::uint32_t>(tiles_x.size()); }
    // Levels 0 .. merged_levels()-1 live in the merged table; coarser ones ("tail" levels,
    // where the painting's region would be thinner than one entry) in a per-painting table.
    std::uint32_t merged_levels() const;
};

struct VtLayout {
    std::uint32_t tile_size = 0, border = 0;
    std::uint32_t table_w = 0, table_h = 0;  // merged Mc x Nc
    std::vector<VtPainting> paintings;
    std::uint32_t payload() const { return tile_size - 2 * border; }
    std::size_t tile_bytes() const { return std::size_t(tile_size) * tile_size * 3; }

    static VtLayout from_pack(const TilePack& pack);
    // The geometry the pack uses (levels until the painting fits one tile), for tests and
    // synthetic layouts; paintings are placed side by side along x.
    static VtLayout make(std::uint32_t tile_size, std::uint32_t border,
                         const std::vector<std::pair<std::uint32_t, std::uint32_t>>& sizes);
    // InvalidArgument unless the layout is consistent (offsets aligned and inside the table).
    void validate() const;
};

}  // namespace gigascroll
