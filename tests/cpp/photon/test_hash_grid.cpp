// The hash grid at a radius too small for a dense table, and refused radii.
#include <gtest/gtest.h>

#include <cmath>

#include "common/error.h"
#include "photon/hash_grid.h"
#include "photon/random_photons.h"

using namespace gigascroll;

TEST(PhotonSearch, TinyRadiusFallsBackToHashedTableWithoutOverflow) {
    // 2 units at r = 1e-6 would be 2e6^3 = 8e18 dense cells: more than any table, near 2^63.
    const auto ph = random_photons(1000, 5);
    HashGrid grid(ph, 1e-6f);
    EXPECT_FALSE(grid.dense());
    EXPECT_LE(grid.cell_count(), 4096u);  // about twice the photon count
    float r2 = 1e-12f;
    int found = 0;
    grid.for_each_in_radius(ph[10].p, r2, [&](const Photon&, float) { ++found; });
    EXPECT_EQ(found, 1);
    EXPECT_THROW(HashGrid(ph, 0.0f), gigascroll::InvalidArgument);
    EXPECT_THROW(HashGrid(ph, NAN), gigascroll::InvalidArgument);
}
