// Painting and pack geometry: levels, tiles per level and page-table sizes.
#include <gtest/gtest.h>

#include "common/error.h"
#include "pack/geometry.h"

using namespace gigascroll;

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
