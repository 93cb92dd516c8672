// Geometry shared by the pack builder and reader: the mip chain of one painting cut into
// tiles of `tile_size` texels with a `border` on each side (payload P = tile_size - 2 border).
//   level l is ceil(W / 2^l) x ceil(H / 2^l); tile (tx, ty) of level l holds texels
//   [tx P - border, tx P + P + border) x [ty P - border, ...), clamped to the real extent;
//   levels stop at the first one where the whole painting fits in one tile.
//   The painting's page table is the power-of-two grid Mp x Np >= its level-0 tile grid;
//   uv_scale = (W / (Mp P), H / (Np P)) hides the padding (seed 000 eqs 3, 4).
#pragma once
#include <cstdint>
#include <vector>

namespace gigascroll {

struct LevelGeometry {
    std::uint32_t width = 0, height = 0;    // texels
    std::uint32_t tiles_x = 0, tiles_y = 0; // real tiles: ceil(width / P) x ceil(height / P)
    std::uint64_t first_entry = 0;          // index of tile (0, 0) among the painting's entries
};

struct PaintingGeometry {
    std::uint32_t width = 0, height = 0;
    std::uint32_t tile_size = 0, border = 0, payload = 0;
    std::uint32_t table_width = 0, table_height = 0;  // Mp x Np, powers of two
    std::vector<LevelGeometry> levels;
    std::uint64_t tile_count = 0;                     // real tiles over all levels

    double uv_scale_u() const { return double(width) / (double(table_width) * payload); }
    double uv_scale_v() const { return double(height) / (double(table_height) * payload); }
    std::uint32_t level_count() const { return static_cast<std::uint32_t>(levels.size()); }
};

// Validates the tile parameters (InvalidArgument: tile_size <= 2 border, zero-sized image, ...).
void check_tile_parameters(std::uint32_t tile_size, std::uint32_t border);
PaintingGeometry make_geometry(std::uint32_t width, std::uint32_t height,
                               std::uint32_t tile_size, std::uint32_t border);

}  // namespace gigascroll
