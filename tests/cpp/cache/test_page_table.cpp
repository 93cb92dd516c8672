// The page table, kept up to date insert by insert and eviction by eviction, against a
// brute-force rebuild; lookups answer the finest resident ancestor.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "cache/page_table.h"
#include "cache/virtual_texture.h"
#include "pack/geometry.h"
#include "pack/tile_key.h"
#include "support/all_tiles.h"

using namespace gigascroll;

TEST(PageTable, IncrementalUpdatesMatchFullRebuild) {
    // Three paintings of awkward sizes; a small cache so LRU evictions happen constantly.
    const PackGeometry layout = PackGeometry::make(16, 2, {{500, 90}, {37, 301}, {12, 12}});
    std::vector<std::uint8_t> zero(layout.tile_bytes(), 0);
    VirtualTexture vt(layout, 6, 6, [](const TileKey&, std::uint8_t*) {});
    const auto keys = all_tiles(layout);
    std::mt19937 rng(7);
    for (int step = 0; step < 600; ++step) {
        const TileKey k = keys[rng() % keys.size()];
        const auto evicted = vt.insert(k, zero.data());
        EXPECT_TRUE(vt.is_resident(k));
        if (evicted) EXPECT_FALSE(vt.is_resident(*evicted));
        if (step % 25 == 0) ASSERT_TRUE(vt.page_table_matches_rebuild()) << "step " << step;
    }
    EXPECT_TRUE(vt.page_table_matches_rebuild());
    const CacheStats s = vt.stats();
    EXPECT_EQ(s.resident, 36u);
    EXPECT_GT(s.evictions, 0u);
}

TEST(PageTable, LookupIsTheFinestResidentAncestor) {
    const PackGeometry layout = PackGeometry::make(16, 2, {{300, 200}});
    std::vector<std::uint8_t> zero(layout.tile_bytes(), 0);
    VirtualTexture vt(layout, 8, 8, [](const TileKey&, std::uint8_t*) {});
    const auto& pt = layout.paintings[0];
    const std::uint32_t L = pt.levels();
    // Nothing streamed yet: every entry falls back to the finest pinned level (the first
    // tail level, or the coarsest level when there is no tail).
    const std::uint32_t first_pinned = std::min(pt.merged_levels(), L - 1);
    EXPECT_EQ(vt.lookup({0, 0, 5, 5}).level(), first_pinned);
    vt.insert({0, 2, 1, 1}, zero.data());
    vt.insert({0, 0, 5, 5}, zero.data());
    EXPECT_EQ(vt.lookup({0, 0, 5, 5}).level(), 0u);
    EXPECT_EQ(vt.lookup({0, 0, 4, 5}).level(), 2u);  // sibling: its level-2 ancestor (1, 1)
    EXPECT_EQ(vt.lookup({0, 1, 2, 2}).level(), 2u);
    EXPECT_EQ(vt.lookup({0, 0, 0, 0}).level(), first_pinned);  // not under (2, 1, 1)
    EXPECT_EQ(vt.lookup({0, 2, 1, 1}).slot(), vt.lookup({0, 0, 4, 5}).slot());
}
