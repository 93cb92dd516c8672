// Counter-based random numbers: Philox4x32-10 against Random123's known-answer vectors, and
// photon sets of neighbouring seeds (and passes) sharing no more than chance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <set>
#include <tuple>
#include <vector>

#include "photon/photon_tracer.h"
#include "photon/rng.h"
#include "photon/scenes.h"

using namespace gigascroll;

TEST(PhotonRng, Philox4x32_10MatchesKnownAnswers) {
    struct Case {
        std::uint32_t ctr[4], key[2], out[4];
    };
    // Random123 kat_vectors: philox4x32 10 (counter, key) -> output.
    const Case cases[] = {
        {{0, 0, 0, 0}, {0, 0}, {0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}},
        {{0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff}, {0xffffffff, 0xffffffff},
         {0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}},
        {{0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344}, {0xa4093822, 0x299f31d0},
         {0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}},
    };
    for (const Case& c : cases) {
        const Philox4x32Block b = philox4x32_10(c.ctr, c.key);
        for (int i = 0; i < 4; ++i) EXPECT_EQ(b.v[i], c.out[i]) << i;
    }
}

TEST(PhotonRng, StreamsOfNeighbouringSeedsAndIndicesDoNotOverlap) {
    // The first 8 draws of (seed, index) for 4 seeds x 4096 indices: any repeated 64-bit pair
    // of words would show one stream replaying another (chance: ~2^-40 here).
    std::set<std::uint64_t> seen;
    std::size_t draws = 0;
    for (std::uint64_t seed = 0; seed < 4; ++seed)
        for (std::uint64_t i = 0; i < 4096; ++i) {
            Rng rng(seed, stream_id(StreamKind::Photon), i);
            for (int k = 0; k < 4; ++k) {
                const std::uint64_t a = rng.next(), b = rng.next();
                seen.insert((a << 32) | b);
                ++draws;
            }
        }
    EXPECT_EQ(seen.size(), draws);
}

TEST(PhotonRng, UniformIsInUnitIntervalWithTheRightMean) {
    Rng rng(5, stream_id(StreamKind::Pixel), 0);
    double sum = 0;
    const int n = 1 << 20;
    for (int i = 0; i < n; ++i) {
        const float u = rng.uniform();
        ASSERT_GE(u, 0.0f);
        ASSERT_LT(u, 1.0f);
        sum += u;
    }
    EXPECT_NEAR(sum / n, 0.5, 5 * 0.2887 / 1024);  // 5 standard errors
}

namespace {
using Key = std::tuple<float, float, float>;
std::set<Key> positions(const std::vector<Photon>& ph) {
    std::set<Key> s;
    for (const Photon& p : ph) s.insert({p.p.x, p.p.y, p.p.z});
    return s;
}
std::size_t shared(const std::set<Key>& a, const std::set<Key>& b) {
    std::size_t n = 0;
    for (const Key& k : a) n += b.count(k);
    return n;
}
}  // namespace

TEST(PhotonRng, NeighbouringSeedsAndPassesTraceDifferentPhotons) {
    // With hash_combine(seed, i) seeding, seed 1 stored nearly all of seed 0's photons again.
    // Two independent sets of continuous positions share none (a float triple coinciding by
    // chance: ~1e-12 per pair here).
    Scene scene;
    build_cornell(scene, 8, 8);
    scene.commit();
    const auto s0 = positions(trace_photons(scene, 20000, 0, 0));
    const auto s1 = positions(trace_photons(scene, 20000, 1, 0));
    const auto p1 = positions(trace_photons(scene, 20000, 0, 0, nullptr, /*pass=*/1));
    ASSERT_GT(s0.size(), 10000u);
    EXPECT_EQ(shared(s0, s1), 0u);
    EXPECT_EQ(shared(s0, p1), 0u);
    EXPECT_EQ(shared(s0, positions(trace_photons(scene, 20000, 0, 2))), s0.size());  // same seed
}
