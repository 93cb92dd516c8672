// The residency set's finest resident ancestor, and the dense tile index over every tile.
#include <gtest/gtest.h>

#include <cstdint>

#include "common/error.h"
#include "pack/geometry.h"
#include "pack/tile_key.h"
#include "views/residency.h"
#include "views/random_feedback.h"

using namespace gigascroll;

TEST(TileIndex, IsABijectionOverEveryTile) {
    const TileIndex index(small_paintings());
    std::uint64_t expect = 0;
    for (const auto& p : small_paintings()) expect += p.total_tiles();
    ASSERT_EQ(index.size(), expect);
    for (std::uint64_t i = 0; i < index.size(); ++i) ASSERT_EQ(index.index(index.key(i)), i);
    EXPECT_THROW(index.index(pack_request(3, 0, 0, 0)), InvalidArgument);
    EXPECT_THROW(index.index(pack_request(0, 0, 9999, 0)), InvalidArgument);
}

TEST(ResidentSet, FinestResidentAncestor) {
    ResidentSet r({PaintingGeometry(1000, 1000)});  // levels: 9x9, 5x5, 3x3, 2x2, 1x1
    ASSERT_EQ(r.paintings()[0].levels(), 5u);
    const std::uint64_t q = pack_request(0, 0, 7, 8);
    EXPECT_EQ(r.resident_level(q), 4u);  // only the coarsest tile
    r.insert(pack_request(0, 2, 1, 2));
    EXPECT_EQ(r.resident_level(q), 2u);
    r.insert(pack_request(0, 0, 7, 8));
    EXPECT_EQ(r.resident_level(q), 0u);
    EXPECT_EQ(response_of(r, pack_request(0, 1, 3, 4)), pack_request(0, 2, 1, 2));
    EXPECT_THROW(r.resident_level(pack_request(1, 0, 0, 0)), InvalidArgument);
}
