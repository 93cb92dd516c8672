// Photon tracing is deterministic: the same seed gives the same photons for any thread count;
// paths end by Russian roulette alone, memory is bounded by a budget of stored photons; rays
// are checked before they reach Embree.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

#include "common/error.h"

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
    // Small passes are split in chunks of 256 photons and up, on both cores: still the same.
    for (std::uint64_t n : {1ull, 300ull, 1024ull, 5000ull}) {
        const auto s1 = trace_photons(scene, n, 7, 1);
        const auto s2 = trace_photons(scene, n, 7, 2);
        ASSERT_EQ(s1.size(), s2.size()) << n;
        for (std::size_t i = 0; i < s1.size(); ++i) {
            EXPECT_EQ(s1[i].p.x, s2[i].p.x);
            EXPECT_EQ(s1[i].power.y, s2[i].power.y);
        }
    }
}

TEST(PhotonTracer, TracingIntoAReusedVectorGivesTheSamePhotons) {
    // The overload that keeps out's capacity (a gallery relit) overwrites every element,
    // whether out held more photons before or fewer.
    Scene scene;
    build_cornell(scene, 16, 16);
    scene.commit();
    const auto ref_small = trace_photons(scene, 3000, 7, 2), ref_big = trace_photons(scene, 20000, 9, 2);
    std::vector<Photon> out(50000, Photon{{1, 2, 3}, {4, 5, 6}, {7, 8, 9}});
    for (const auto* ref : {&ref_small, &ref_big, &ref_small}) {
        TraceStats st;
        const bool small = ref == &ref_small;
        trace_photons(out, scene, small ? 3000 : 20000, small ? 7 : 9, 2, &st);
        ASSERT_EQ(out.size(), ref->size());
        EXPECT_EQ(st.stored, ref->size());
        for (std::size_t i = 0; i < out.size(); ++i) {
            EXPECT_EQ(out[i].p.x, (*ref)[i].p.x);
            EXPECT_EQ(out[i].p.z, (*ref)[i].p.z);
            EXPECT_EQ(out[i].n.y, (*ref)[i].n.y);
            EXPECT_EQ(out[i].power.x, (*ref)[i].power.x);
        }
    }
}

TEST(PhotonTracer, AShorterPassIsAPrefixOfALongerOne) {
    // Photon i's path depends on (seed, i) alone, so the photons of a pass of n are the first
    // ones of a pass of more (their power scaled by the counts' ratio), whatever the chunking: in the Cornell box (every chunk within
    // its slot of 2 stored per emitted photon) and a furnace of albedo 0.9 (9 stored per
    // emitted one: the chunks spill), on 1 and 2 threads.
    for (float albedo : {0.0f, 0.9f}) {
        Scene scene;
        if (albedo > 0) build_furnace(scene, albedo, 1.0f, 8, 8);
        else build_cornell(scene, 16, 16);
        scene.commit();
        const auto longer = trace_photons(scene, 20000, 5, 2);
        for (unsigned threads : {1u, 2u}) {
            const auto shorter = trace_photons(scene, 5000, 5, threads);
            ASSERT_GT(shorter.size(), 4000u);
            ASSERT_LT(shorter.size(), longer.size());
            for (std::size_t i = 0; i < shorter.size(); ++i) {
                ASSERT_EQ(shorter[i].p.x, longer[i].p.x) << albedo << " " << i;
                ASSERT_EQ(shorter[i].p.y, longer[i].p.y);
                ASSERT_EQ(shorter[i].n.z, longer[i].n.z);
                // Each photon carries the scene's power / n.
                ASSERT_NEAR(shorter[i].power.z, 4 * longer[i].power.z, 1e-5f * shorter[i].power.z);
            }
        }
    }
}

// No bounce cap: in a closed sphere of albedo 0.99 a photon stores rho / (1 - rho) = 99 copies
// on average (the old cap of 256 bounces stored at most 255 and lost 7.7% of the flux).
TEST(PhotonTracer, FurnaceAtAlbedo099StoresTheGeometricMean) {
    Scene scene;
    build_furnace(scene, 0.99f, 1.0f, 8, 8);
    scene.commit();
    const std::uint64_t n = 4000;
    TraceStats st;
    const auto ph = trace_photons(scene, n, 3, 2, &st);
    const double rho = 0.99, mean = n * rho / (1 - rho);
    const double sigma = std::sqrt(n * rho) / (1 - rho);  // sd of a sum of n geometric counts
    EXPECT_NEAR(double(ph.size()), mean, 5 * sigma);
    EXPECT_EQ(st.stored, ph.size());
}

// Past the stored-photon budget: InvalidArgument naming the memory, for any thread count,
// and the same photons as always when under it.
TEST(PhotonTracer, BudgetOfStoredPhotonsIsAnErrorWithTheMemory) {
    Scene scene;
    build_furnace(scene, 0.999f, 1.0f, 8, 8);
    scene.commit();
    for (unsigned threads : {1u, 2u}) {
        try {
            trace_photons(scene, 5000, 1, threads, nullptr, 0, 200000);
            ADD_FAILURE() << "no error past the budget";
        } catch (const InvalidArgument& e) {
            EXPECT_NE(std::string(e.what()).find("MiB, the memory budget"), std::string::npos) << e.what();
        }
    }
    const auto a = trace_photons(scene, 30, 1, 1, nullptr, 0, 200000);
    const auto b = trace_photons(scene, 30, 1, 2);
    ASSERT_EQ(a.size(), b.size());
    EXPECT_THROW(trace_photons(scene, (std::uint64_t(1) << 32) + 1, 1), InvalidArgument);
    EXPECT_THROW(trace_photons(scene, 10, 1, 5000), InvalidArgument);
}

// Every ray is checked before it reaches Embree (which aborts on invalid ones).
TEST(Scene, InvalidRaysAreInvalidArgumentNotAnAbort) {
    Scene scene;
    build_cornell(scene, 16, 16);
    scene.commit();
    Hit hit;
    const float nan = std::nanf(""), inf = INFINITY;
    EXPECT_THROW(scene.intersect({0, 0, 0}, {nan, 0, 1}, hit), InvalidArgument);
    EXPECT_THROW(scene.intersect({2e18f, 0, 0}, {0, 0, 1}, hit), InvalidArgument);
    EXPECT_THROW(scene.occluded({0, 0, 0}, {0, inf, 1}, 1.0f), InvalidArgument);
    EXPECT_THROW(scene.intersect_checked({0, 0, 0}, {0, 0, 0}, hit), InvalidArgument);
    EXPECT_THROW(scene.intersect_checked({1e13f, 0, 0}, {0, 0, 1}, hit), InvalidArgument);
    EXPECT_TRUE(scene.intersect_checked({-0.9f, 0, 0.5f}, {-1, 0, 0}, hit));
    EXPECT_NEAR(hit.t, 0.1f, 1e-5f);
}
