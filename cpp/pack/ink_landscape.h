// The built-in painting: a deterministic procedural "ink landscape" standing in for the
// real gigapixel scans (layered mountains in ink wash, paper fibre, tree and grass strokes
// down to single pixels, so every mip level differs from the next). Any band of rows can be
// rendered on its own, so arbitrarily large paintings stream out in constant memory.
#pragma once
#include <cstdint>

namespace gigascroll {

// Writes rows [y0, y0 + rows) of a width x height painting as RGB8 into out
// (rows * width * 3 bytes). Same (width, height, seed) -> same pixels, whatever the banding.
void render_ink_landscape(std::uint32_t width, std::uint32_t height, std::uint32_t y0,
                          std::uint32_t rows, std::uint64_t seed, std::uint8_t* out,
                          unsigned threads = 0);

}  // namespace gigascroll
