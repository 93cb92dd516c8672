// The tile cache: LRU eviction that keeps the pinned tiles, and refused sizes and keys.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "common/error.h"
#include "cache/virtual_texture.h"
#include "pack/geometry.h"
#include "pack/tile_key.h"

using namespace gigascroll;

TEST(VirtualTexture, LruEvictsLeastRecentlyUsedAndKeepsPinned) {
    const PackGeometry layout = PackGeometry::make(16, 2, {{200, 30}});
    std::vector<std::uint8_t> zero(layout.tile_bytes(), 0);
    VirtualTexture vt(layout, 4, 3, [](const TileKey&, std::uint8_t*) {});
    const std::uint64_t pinned = vt.stats().pinned;
    const std::uint32_t free_slots = 12 - pinned;
    ASSERT_GE(free_slots, 3u);
    for (std::uint32_t i = 0; i < free_slots; ++i) EXPECT_FALSE(vt.insert({0, 0, i, 0}, zero.data()));
    // Touch tile 0, so tile 1 is the least recently used.
    EXPECT_TRUE(vt.request({{0, 0, 0, 0}, {0, 0, 9, 0}, {0, 0, 9, 0}}).size() == 1);
    const auto ev = vt.insert({0, 0, 10, 0}, zero.data());
    ASSERT_TRUE(ev);
    EXPECT_EQ(*ev, (TileKey{0, 0, 1, 0}));
    const CacheStats s = vt.stats();
    EXPECT_EQ(s.hits, 1u);
    EXPECT_EQ(s.misses, 2u);
    EXPECT_EQ(s.evictions, 1u);
    EXPECT_EQ(s.resident, 12u);
    const auto& pt = layout.paintings[0];
    EXPECT_TRUE(vt.is_pinned({0, pt.levels() - 1, 0, 0}));
}

TEST(VirtualTexture, RejectsTooFewSlotsAndBadKeys) {
    const PackGeometry layout = PackGeometry::make(128, 4, {{152089, 6083}});
    EXPECT_THROW(VirtualTexture(layout, 4, 4, [](const TileKey&, std::uint8_t*) {}), InvalidArgument);
    VirtualTexture vt(layout, 5, 5, [](const TileKey&, std::uint8_t*) {});
    std::vector<std::uint8_t> zero(layout.tile_bytes(), 0);
    EXPECT_THROW(vt.insert({0, 0, 1268, 0}, zero.data()), InvalidArgument);
    EXPECT_THROW(vt.insert({1, 0, 0, 0}, zero.data()), InvalidArgument);
    EXPECT_THROW(vt.insert({0, 12, 0, 0}, zero.data()), InvalidArgument);
}
