// Loading strategies (VT-mobile-VR §4.2.2): capped direct loading and mip-by-mip loading,
// against hand-worked expectations on a small residency set.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "common/error.h"
#include "loading/load_strategy.h"
#include "views/residency.h"

using namespace gigascroll;

namespace {
std::vector<std::uint64_t> level0_row(std::uint32_t n) {
    std::vector<std::uint64_t> keys;
    for (std::uint32_t x = 0; x < n; ++x) keys.push_back(pack_request(0, 0, x, 0));
    return keys;
}
}  // namespace

TEST(DirectLoading, CapsPerFrameAndCarriesTheRestUntilReplaced) {
    const ResidentSet resident({PaintingGeometry(120 * 40, 120)});  // 40 x 1 level-0 tiles
    DirectLoading direct(16);
    const auto commands = level0_row(40);
    direct.set_commands(commands);
    const auto f1 = direct.issue(resident);
    EXPECT_EQ(f1, std::vector<std::uint64_t>(commands.begin(), commands.begin() + 16));
    const auto f2 = direct.issue(resident);
    EXPECT_EQ(f2, std::vector<std::uint64_t>(commands.begin() + 16, commands.begin() + 32));
    EXPECT_EQ(direct.backlog(), 8u);
    // A new command set replaces the backlog; tiles in flight are not issued twice.
    direct.set_commands(commands);
    const auto f3 = direct.issue(resident);
    EXPECT_EQ(f3, std::vector<std::uint64_t>(commands.begin() + 32, commands.end()));
    EXPECT_EQ(direct.in_flight(), 40u);
    // Loaded and resident tiles are skipped; loaded-but-evicted ones are asked again.
    ResidentSet now = resident;
    for (std::size_t i = 0; i < 20; ++i) now.insert(commands[i]);
    direct.loaded(std::span(commands).first(24));
    direct.set_commands(commands);
    EXPECT_EQ(direct.issue(now), std::vector<std::uint64_t>(commands.begin() + 20, commands.begin() + 24));
    EXPECT_THROW(DirectLoading(0), InvalidArgument);
}

TEST(MipByMipLoading, LoadsCoarsestMissingAncestorFirst) {
    // 1000 x 1000 texels: levels 9x9, 5x5, 3x3, 2x2, 1x1; level 4 always resident.
    ResidentSet resident({PaintingGeometry(1000, 1000)});
    MipByMipLoading mip(16);
    const std::uint64_t q = pack_request(0, 0, 7, 8), q2 = pack_request(0, 0, 8, 8);
    // Only level 4 resident: each needs its level-3 ancestor, (0, 1) and (1, 1); a second
    // command under the same ancestor adds nothing.
    const std::vector<std::uint64_t> l3{pack_request(0, 3, 0, 1), pack_request(0, 3, 1, 1)};
    EXPECT_EQ(mip.issue(std::vector{q, q2, pack_request(0, 0, 6, 8)}, resident), l3);
    // In flight: not asked again.
    EXPECT_TRUE(mip.issue(std::vector{q}, resident).empty());
    mip.loaded(l3);
    for (auto k : l3) resident.insert(k);
    resident.insert(pack_request(0, 2, 1, 2));
    // q's chain now stops at level 2 (1, 2): the next is level 1 (3, 4); q2's too (4, 4)
    // under level 2 (2, 2), missing, so q2 asks (2, 2) at level 2 first.
    EXPECT_EQ(mip.issue(std::vector{q, q2}, resident),
              (std::vector{pack_request(0, 2, 2, 2), pack_request(0, 1, 3, 4)}));
    // Resident requests ask nothing; the cap holds, coarsest first.
    resident.insert(q);
    EXPECT_TRUE(mip.issue(std::vector{q}, resident).empty());
    MipByMipLoading capped(1);
    EXPECT_EQ(capped.issue(std::vector{pack_request(0, 0, 0, 0), pack_request(0, 3, 0, 0)}, resident),
              std::vector{pack_request(0, 3, 0, 0)});
}
