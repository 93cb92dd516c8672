#include "pack/mip_reducer.h"

#include <algorithm>
#include <cstring>

#include "common/parallel.h"

namespace gigascroll {

MipReducer::MipReducer(const PaintingGeometry& geometry, unsigned threads)
    : geometry_(geometry), threads_(threads), levels_(geometry.levels()) {
    for (std::size_t l = 0; l < levels_.size(); ++l) {
        Level& lv = levels_[l];
        lv.geo = geometry.level(std::uint32_t(l));
        lv.shift = static_cast<std::uint32_t>(l);
        if (l > 0) lv.acc.assign(std::size_t(lv.geo.width) * 3, 0);
    }
}

void MipReducer::drop_rows(std::size_t l, std::uint32_t keep_from) {
    Level& lv = levels_[l];
    if (keep_from <= lv.win_base) return;
    const std::size_t row_bytes = std::size_t(lv.geo.width) * 3;
    const std::uint32_t drop = keep_from - lv.win_base;
    std::memmove(lv.window.data(), lv.window.data() + drop * row_bytes,
                 (lv.win_rows - drop) * row_bytes);
    lv.win_rows -= drop;
    lv.win_base = keep_from;
    lv.window.resize(lv.win_rows * row_bytes);
}

void MipReducer::add_rows(const std::uint8_t* rgb, std::uint32_t rows) {
    const PaintingGeometry& g = geometry_;
    const std::uint32_t y0 = levels_[0].rows_done;

    // Rows each level completes in this band; grow the windows before the parallel part.
    std::vector<std::uint32_t> done(levels_.size());
    done[0] = y0 + rows;
    for (std::size_t l = 1; l < levels_.size(); ++l) {
        const Level& up = levels_[l - 1];
        done[l] = done[l - 1] == up.geo.height ? levels_[l].geo.height : done[l - 1] / 2;
    }
    for (std::size_t l = 0; l < levels_.size(); ++l) {
        Level& lv = levels_[l];
        const std::uint32_t added = done[l] - lv.rows_done;
        lv.window.resize(std::size_t(lv.win_rows + added) * lv.geo.width * 3);
    }

    // Column strips aligned to 2^(levels-1) stay independent through the whole chain.
    const std::uint32_t align = 1u << (levels_.size() - 1);
    const std::uint32_t strip = std::max<std::uint32_t>(align, ((4096 + align - 1) / align) * align);
    const std::size_t strips = (g.width() + strip - 1) / strip;
    parallel_for(strips, 1, [&](std::size_t b, std::size_t e) {
        for (std::size_t s = b; s < e; ++s) {
            const std::uint32_t x0 = static_cast<std::uint32_t>(s * strip);
            const std::uint32_t x1 = std::min<std::uint32_t>(g.width(), x0 + strip);
            reduce_strip(x0, x1, rgb, y0, rows);
        }
    }, threads_);

    for (std::size_t l = 0; l < levels_.size(); ++l) {
        Level& lv = levels_[l];
        lv.win_rows += done[l] - lv.rows_done;
        lv.rows_done = done[l];
    }
}

// Level 0 rows [y_begin, y_begin + rows), columns [x0, x1): copy into the window and cascade
// the sums down the chain. Only this strip's columns of any buffer are touched.
void MipReducer::reduce_strip(std::uint32_t x0, std::uint32_t x1, const std::uint8_t* rgb,
                               std::uint32_t y_begin, std::uint32_t rows) {
    Level& l0 = levels_[0];
    const std::uint32_t W = l0.geo.width;
    for (std::uint32_t i = 0; i < rows; ++i) {
        const std::uint32_t y = y_begin + i;
        const std::uint8_t* src = rgb + (std::size_t(i) * W + x0) * 3;
        std::uint8_t* dst = l0.window.data() + (std::size_t(y - l0.win_base) * W + x0) * 3;
        std::memcpy(dst, src, std::size_t(x1 - x0) * 3);
        if (levels_.size() == 1) continue;
        std::uint64_t* acc = levels_[1].acc.data();
        const std::uint32_t X0 = x0 >> 1, X1 = (x1 + 1) >> 1;
        for (std::uint32_t X = X0; X < X1; ++X) {
            const std::uint32_t xa = 2 * X, xb = std::min(2 * X + 1, W - 1);
            const std::uint8_t* a = src + std::size_t(xa - x0) * 3;
            for (int c = 0; c < 3; ++c) acc[3 * X + c] += a[c];
            if (xb != xa) {
                const std::uint8_t* bp = src + std::size_t(xb - x0) * 3;
                for (int c = 0; c < 3; ++c) acc[3 * X + c] += bp[c];
            }
        }
        if ((y & 1) || y == l0.geo.height - 1) finish_row(1, y >> 1, X0, X1);
    }
}

// Row y of level l is complete in columns [x0, x1) of that level: turn its sums into texels,
// pass them on to level l+1 and recurse when that row completes too.
void MipReducer::finish_row(std::size_t l, std::uint32_t y, std::uint32_t x0, std::uint32_t x1) {
    Level& lv = levels_[l];
    const PaintingGeometry& g = geometry_;
    const std::uint32_t s = lv.shift;
    const std::uint64_t full = 1ull << (2 * s);
    const std::uint64_t cy =
        std::min<std::uint64_t>(g.height(), (std::uint64_t(y) + 1) << s) - (std::uint64_t(y) << s);
    std::uint64_t* acc = lv.acc.data();
    std::uint8_t* dst = lv.window.data() + std::size_t(y - lv.win_base) * lv.geo.width * 3;
    const bool last_level = l + 1 == levels_.size();
    std::uint64_t* next = last_level ? nullptr : levels_[l + 1].acc.data();
    for (std::uint32_t x = x0; x < x1; ++x) {
        const std::uint64_t cx =
            std::min<std::uint64_t>(g.width(), (std::uint64_t(x) + 1) << s) - (std::uint64_t(x) << s);
        const std::uint64_t count = cx * cy;
        std::uint64_t* a = acc + 3 * std::size_t(x);
        if (count == full) {
            for (int c = 0; c < 3; ++c) dst[3 * x + c] = std::uint8_t((a[c] + full / 2) >> (2 * s));
        } else {
            for (int c = 0; c < 3; ++c) dst[3 * x + c] = std::uint8_t((a[c] + count / 2) / count);
        }
        if (next) {
            std::uint64_t* n = next + 3 * std::size_t(x >> 1);
            for (int c = 0; c < 3; ++c) n[c] += a[c];
        }
        a[0] = a[1] = a[2] = 0;
    }
    if (!last_level && ((y & 1) || y == lv.geo.height - 1))
        finish_row(l + 1, y >> 1, x0 >> 1, (x1 + 1) >> 1);
}

}  // namespace gigascroll
