// Painting and pack geometry: levels, tiles per level and page-table sizes.
#include <gtest/gtest.h>

#include <cstdint>

#include "common/error.h"
#include "pack/geometry.h"

using namespace gigascroll;

TEST(PaintingGeometry, ScrollPyramidMatchesDirectCount) {
    const PaintingGeometry t(152089, 6083);  // the seed's scroll, 128-texel tiles, 4-texel border
    EXPECT_EQ(t.payload(), 120u);
    // Direct count: halve (rounding up) until one 120-texel tile holds the level.
    std::uint64_t w = 152089, h = 6083, total = 0;
    std::uint32_t levels = 0;
    for (;;) {
        const std::uint64_t tx = (w + 119) / 120, ty = (h + 119) / 120;
        EXPECT_EQ(t.tiles_x(levels), tx);
        EXPECT_EQ(t.tiles_y(levels), ty);
        total += tx * ty;
        ++levels;
        if (tx == 1 && ty == 1) break;
        w = (w + 1) / 2, h = (h + 1) / 2;
    }
    EXPECT_EQ(t.levels(), levels);
    EXPECT_EQ(t.levels(), 12u);
    EXPECT_EQ(t.total_tiles(), total);
    EXPECT_EQ(t.page_table_width(), 2048u);  // 1268 tiles -> 2048
    EXPECT_EQ(t.page_table_height(), 64u);   // 51 tiles -> 64
    EXPECT_THROW(PaintingGeometry(0, 10), InvalidArgument);
    EXPECT_THROW(PaintingGeometry(10, 10, 8, 4), InvalidArgument);
}

TEST(PackGeometry, Table4PaintingHasPowerOfTwoPageTable) {
    const PaintingGeometry g = PaintingGeometry(152089, 6083, 128, 4);
    EXPECT_EQ(g.page_table_width(), 2048u);
    EXPECT_EQ(g.page_table_height(), 64u);
    EXPECT_EQ(g.level(0).tiles_x, 1268u);
    EXPECT_EQ(g.level(0).tiles_y, 51u);
    EXPECT_EQ(g.levels(), 12u);
    EXPECT_LE(g.level(g.levels() - 1).width, 120u);
    EXPECT_GT(g.level(g.levels() - 2).width, 120u);
    EXPECT_THROW(PaintingGeometry(10, 10, 8, 4), InvalidArgument);
    EXPECT_THROW(PaintingGeometry(0, 10, 128, 4), InvalidArgument);
}

TEST(PackGeometry, TailLevelsOfTheScroll) {
    // The seed's scroll: Mp = 2048, Np = 64, levels 0..11; levels 7..11 are the tail (21 tiles).
    const PackGeometry layout = PackGeometry::make(128, 4, {{152089, 6083}});
    const PaintingGeometry& p = layout.paintings[0];
    EXPECT_EQ(p.page_table_width(), 2048u);
    EXPECT_EQ(p.page_table_height(), 64u);
    EXPECT_EQ(p.levels(), 12u);
    EXPECT_EQ(p.merged_levels(), 7u);
    std::uint32_t tail = 0;
    for (std::uint32_t l = 7; l < 12; ++l) tail += p.tiles_x(l) * p.tiles_y(l);
    EXPECT_EQ(tail, 21u);
    EXPECT_EQ(p.tiles_x(11) * p.tiles_y(11), 1u);
}
