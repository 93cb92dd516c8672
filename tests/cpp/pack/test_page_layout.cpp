// Page-table layouts (shelf and BRKGA) against a brute-force overlap check at every level.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <vector>

#include "common/error.h"
#include "pack/page_layout.h"

using namespace gigascroll;

TEST(PageLayout, PackersAreAlignedDisjointAtEveryLevelAndDeterministic) {
    std::mt19937 rng(7);
    for (int trial = 0; trial < 10; ++trial) {
        std::vector<TableSize> tables(1 + rng() % 12);
        for (auto& t : tables) t = {1u << (rng() % 6), 1u << (rng() % 6)};
        for (const PageLayout& layout : {shelf_layout(tables), brkga_layout(tables, {.seed = 3})}) {
            ASSERT_NO_THROW(check_layout(tables, layout));
            // Brute force over every page-table level a table still covers whole entries.
            for (std::uint32_t l = 0; (1u << l) <= std::max(layout.width, layout.height); ++l) {
                const std::uint32_t gw = std::max(1u, layout.width >> l), gh = std::max(1u, layout.height >> l);
                std::vector<int> grid(std::size_t(gw) * gh, 0);
                for (std::size_t i = 0; i < tables.size(); ++i) {
                    if ((1u << l) > std::min(tables[i].width, tables[i].height)) continue;
                    const auto [x, y] = layout.offsets[i];
                    ASSERT_EQ((x >> l) << l, x);
                    ASSERT_EQ((y >> l) << l, y);
                    for (std::uint32_t yy = y >> l; yy < (y >> l) + (tables[i].height >> l); ++yy)
                        for (std::uint32_t xx = x >> l; xx < (x >> l) + (tables[i].width >> l); ++xx)
                            ASSERT_EQ(++grid[std::size_t(yy) * gw + xx], 1);
                }
            }
        }
        const PageLayout a = brkga_layout(tables, {.seed = 11}), b = brkga_layout(tables, {.seed = 11});
        EXPECT_EQ(a.offsets, b.offsets);
        EXPECT_GE(a.fill_ratio, shelf_layout(tables).fill_ratio);
    }
    EXPECT_THROW(shelf_layout({{3, 4}}), InvalidArgument);
    EXPECT_THROW(check_layout({{4, 4}, {4, 4}}, PageLayout{8, 8, {{0, 0}, {0, 0}}, 0}), InvalidArgument);
    EXPECT_THROW(check_layout({{4, 4}}, PageLayout{8, 8, {{2, 0}}, 0}), InvalidArgument);
}

TEST(PageLayout, WorkBudgetKeepsTheLayoutValidAndNoWorseThanShelf) {
    // Tables the shelf packer cannot place optimally, with budgets from "no GA at all" up.
    std::mt19937 rng(5);
    std::vector<TableSize> tables(300);
    for (auto& t : tables) t = {1u << (rng() % 7), 1u << (rng() % 3)};
    const PageLayout shelf = shelf_layout(tables);
    for (std::uint64_t budget : {std::uint64_t(1), std::uint64_t(100'000), std::uint64_t(20'000'000)}) {
        BrkgaOptions o;
        o.seed = 2;
        o.work_budget = budget;
        const PageLayout a = brkga_layout(tables, o);
        ASSERT_NO_THROW(check_layout(tables, a));
        EXPECT_GE(a.fill_ratio, shelf.fill_ratio);
        EXPECT_EQ(a.offsets, brkga_layout(tables, o).offsets);  // deterministic (a work count, not a clock)
    }
}

TEST(PageLayout, ShelfMethodDoesNotRunTheGa) {
    const std::vector<TableSize> tables{{4, 4}, {2, 8}, {1, 1}};
    const PlannedLayout p = plan_layout(tables, "shelf", 0);
    EXPECT_EQ(p.brkga.width, 0u);
    EXPECT_EQ(p.chosen.offsets, p.shelf.offsets);
    EXPECT_GT(plan_layout(tables, "brkga", 0).brkga.width, 0u);
}
