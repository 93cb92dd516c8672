// The mip chain of one painting, built band by band from level-0 rows (the pack builder's
// first stage). A mip texel is the rounded average of the real level-0 pixels under it: each
// level keeps the exact 64-bit sums of its texels' level-0 pixels and their counts, never
// averages of averages, so padding cannot bleed in and odd sizes are exact.
//
// Column strips aligned to 2^(levels-1) level-0 pixels are independent through the whole
// chain, so each of `threads` threads cascades its strips through every level. Each level
// keeps a window of completed texel rows; its consumer (the builder cutting tiles) drops the
// rows it no longer needs, so memory grows with the width, not the area.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pack/geometry.h"

namespace gigascroll {

class MipReducer {
public:
    struct Level {
        LevelGeometry geo;
        std::uint32_t shift = 0;             // l: a texel covers 2^l x 2^l level-0 pixels
        std::vector<std::uint8_t> window;    // RGB texel rows [win_base, win_base + win_rows)
        std::uint32_t win_base = 0, win_rows = 0;
        std::uint32_t rows_done = 0;         // rows of this level completed so far
        std::vector<std::uint64_t> acc;      // level-0 sums of the row in progress (l >= 1)
    };

    MipReducer(const PaintingGeometry& geometry, unsigned threads);

    // The next `rows` level-0 rows (rows x width x 3 bytes); the caller keeps bands to at
    // most one payload height, which bounds the windows.
    void add_rows(const std::uint8_t* rgb, std::uint32_t rows);
    // Drops level l's rows below keep_from from its window.
    void drop_rows(std::size_t l, std::uint32_t keep_from);

    std::size_t level_count() const { return levels_.size(); }
    const Level& level(std::size_t l) const { return levels_[l]; }

private:
    void reduce_strip(std::uint32_t x0, std::uint32_t x1, const std::uint8_t* rgb,
                      std::uint32_t y_begin, std::uint32_t rows);
    void finish_row(std::size_t l, std::uint32_t y, std::uint32_t x0, std::uint32_t x1);

    PaintingGeometry geometry_;
    unsigned threads_;
    std::vector<Level> levels_;
};

}  // namespace gigascroll
