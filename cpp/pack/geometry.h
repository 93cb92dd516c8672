// Geometry of tile packs, the one source of truth for the builder, the reader, the views and
// the runtime. A painting's mip chain is cut into tiles of `tile_size` texels with a `border`
// on each side (payload P = tile_size - 2 border):
//   level l is ceil(W / 2^l) x ceil(H / 2^l); tile (tx, ty) of level l holds texels
//   [tx P - border, tx P + P + border) x [ty P - border, ...), clamped to the real extent;
//   levels stop at the first one where the whole painting fits in one tile.
//   The painting's page table is the power-of-two grid Mp x Np >= its level-0 tile grid;
//   uv_scale = (W / (Mp P), H / (Np P)) hides the padding (VT-mobile-VR eqs 3, 4).
// In a pack each painting's page table sits at an offset in the merged Mc x Nc table (a
// multiple of its own Mp, Np) and its tiles' index entries start at first_entry; a tile's
// entry is first_entry + tile_index(l, tx, ty), the one tile index formula (Vulkan-SVT's page
// index: levels 0..l-1 first, row-major inside a level).
#pragma once
#include <cstdint>
#include <utility>
#include <vector>

namespace gigascroll {

struct LevelGeometry {
    std::uint32_t width = 0, height = 0;    // texels
    std::uint32_t tiles_x = 0, tiles_y = 0; // real tiles: ceil(width / P) x ceil(height / P)
    std::uint64_t first_tile = 0;           // tile_index of tile (0, 0) of this level
};

class PaintingGeometry {
public:
    PaintingGeometry() = default;
    // InvalidArgument for bad tile parameters or an empty or oversized image.
    PaintingGeometry(std::uint32_t width, std::uint32_t height, std::uint32_t tile_size = 128,
                     std::uint32_t border = 4);

    std::uint32_t width() const { return width_; }
    std::uint32_t height() const { return height_; }
    std::uint32_t tile_size() const { return tile_size_; }
    std::uint32_t border() const { return border_; }
    std::uint32_t payload() const { return payload_; }
    std::uint32_t levels() const { return static_cast<std::uint32_t>(levels_.size()); }
    const LevelGeometry& level(std::uint32_t l) const { return levels_.at(l); }
    std::uint32_t level_width(std::uint32_t l) const { return level(l).width; }
    std::uint32_t level_height(std::uint32_t l) const { return level(l).height; }
    std::uint32_t tiles_x(std::uint32_t l) const { return level(l).tiles_x; }
    std::uint32_t tiles_y(std::uint32_t l) const { return level(l).tiles_y; }
    std::uint64_t tile_count(std::uint32_t l) const {
        return std::uint64_t(tiles_x(l)) * tiles_y(l);
    }
    // Real tiles of all levels together, and the first tile index of a level (level ==
    // levels() gives the total).
    std::uint64_t total_tiles() const { return total_tiles_; }
    std::uint64_t level_offset(std::uint32_t l) const {
        return l == levels() ? total_tiles_ : level(l).first_tile;
    }
    // The one tile index formula: the tile's position among the painting's tiles.
    std::uint64_t tile_index(std::uint32_t l, std::uint32_t tx, std::uint32_t ty) const {
        const LevelGeometry& lv = levels_[l];
        return lv.first_tile + std::uint64_t(ty) * lv.tiles_x + tx;
    }

    // Level-0 page table Mp x Np: the next powers of two of the level-0 tile counts.
    std::uint32_t page_table_width() const { return table_width_; }
    std::uint32_t page_table_height() const { return table_height_; }
    double uv_scale_u() const { return double(width_) / (double(table_width_) * payload_); }
    double uv_scale_v() const { return double(height_) / (double(table_height_) * payload_); }
    // Levels 0 .. merged_levels()-1 live in the merged page table; coarser "tail" levels,
    // where the painting's region would be thinner than one entry, in a per-painting table.
    std::uint32_t merged_levels() const;
    // Whether every tile coordinate fits the 16 bits of a request key (pack/tile_key.h).
    bool fits_request_key() const { return tiles_x(0) <= 65536 && tiles_y(0) <= 65536; }

    // Where the painting sits in its pack.
    std::uint32_t table_x() const { return table_x_; }
    std::uint32_t table_y() const { return table_y_; }
    std::uint64_t first_entry() const { return first_entry_; }
    void place(std::uint32_t table_x, std::uint32_t table_y, std::uint64_t first_entry) {
        table_x_ = table_x, table_y_ = table_y, first_entry_ = first_entry;
    }

private:
    std::uint32_t width_ = 0, height_ = 0, tile_size_ = 0, border_ = 0, payload_ = 0;
    std::uint32_t table_width_ = 0, table_height_ = 0;
    std::uint32_t table_x_ = 0, table_y_ = 0;
    std::uint64_t first_entry_ = 0;
    std::vector<LevelGeometry> levels_;
    std::uint64_t total_tiles_ = 0;
};

// The paintings of a pack (or of a synthetic layout) and their merged page table: what the
// runtime needs to know.
struct PackGeometry {
    std::uint32_t tile_size = 0, border = 0;
    std::uint32_t table_width = 0, table_height = 0;  // merged Mc x Nc
    std::vector<PaintingGeometry> paintings;

    std::uint32_t payload() const { return tile_size - 2 * border; }
    std::size_t tile_bytes() const { return std::size_t(tile_size) * tile_size * 3; }

    // Paintings of these sizes side by side along x, each table aligned to its own size (for
    // tests and synthetic layouts; a pack's layout comes from its page-layout packer).
    static PackGeometry make(std::uint32_t tile_size, std::uint32_t border,
                             const std::vector<std::pair<std::uint32_t, std::uint32_t>>& sizes);
    // InvalidArgument unless the runtime can use it: border >= 1, every table a power of two,
    // aligned, inside the merged table, tile coordinates within the tile key's 20 bits.
    void validate() const;
};

// Validates the tile parameters (InvalidArgument: tile_size <= 2 border, ...).
void check_tile_parameters(std::uint32_t tile_size, std::uint32_t border);

}  // namespace gigascroll
