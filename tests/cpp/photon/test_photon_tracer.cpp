// Photon tracing is deterministic: the same seed gives the same photons for any thread count.
#include <gtest/gtest.h>

#include <cstddef>

#include "photon/photon_tracer.h"
#include "photon/scene.h"
#include "photon/scenes.h"

using namespace gigascroll;

TEST(PhotonTracer, SameSeedSamePhotonsForAnyThreadCount) {
    Scene scene;
    build_cornell(scene, 16, 16);
    scene.commit();
    const auto a = trace_photons(scene, 20000, 7, 1);
    const auto b = trace_photons(scene, 20000, 7, 2);
    const auto c = trace_photons(scene, 20000, 8, 2);
    ASSERT_EQ(a.size(), b.size());
    ASSERT_GT(a.size(), 10000u);
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].p.x, b[i].p.x);
        EXPECT_EQ(a[i].power.y, b[i].power.y);
    }
    EXPECT_NE(a.size() == c.size() && a[0].p.x == c[0].p.x, true);
}
