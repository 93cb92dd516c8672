// The synthetic ink landscape renders any band of rows the same as the whole image.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "common/error.h"
#include "pack/ink_landscape.h"

using namespace gigascroll;

TEST(InkLandscape, BandsAreIndependent) {
    const std::uint32_t w = 300, h = 50;
    std::vector<std::uint8_t> whole(std::size_t(w) * h * 3), band(std::size_t(w) * 10 * 3);
    render_ink_landscape(w, h, 0, h, 1, whole.data(), 2);
    render_ink_landscape(w, h, 20, 10, 1, band.data(), 1);
    EXPECT_TRUE(std::equal(band.begin(), band.end(), whole.begin() + std::size_t(20) * w * 3));
    EXPECT_THROW(render_ink_landscape(w, h, 45, 10, 1, band.data()), InvalidArgument);
}
