// The photon map's search structures (dense and hashed grid, k-d tree) against brute force:
// radius and k-nearest queries, and the empty map.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <random>
#include <utility>
#include <vector>

#include "common/vec3.h"
#include "photon/hash_grid.h"
#include "photon/photon_map.h"
#include "photon/random_photons.h"

using namespace gigascroll;

namespace {

std::vector<Vec3f> brute_radius(const std::vector<Photon>& ph, Vec3f q, float r) {
    std::vector<Vec3f> out;
    for (const auto& p : ph)
        if (dot(p.p - q, p.p - q) <= r * r) out.push_back(p.p);
    return out;
}

bool less3(Vec3f a, Vec3f b) { return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z))); }

std::vector<Vec3f> positions(const PhotonMap& m, const std::vector<std::uint64_t>& idx) {
    std::vector<Vec3f> out;
    for (auto i : idx) out.push_back(m.photons()[i].p);
    return out;
}

void expect_same_set(std::vector<Vec3f> a, std::vector<Vec3f> b) {
    std::sort(a.begin(), a.end(), less3);
    std::sort(b.begin(), b.end(), less3);
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_EQ(a[i].x, b[i].x);
        EXPECT_EQ(a[i].y, b[i].y);
        EXPECT_EQ(a[i].z, b[i].z);
    }
}

}  // namespace

TEST(PhotonSearch, RadiusQueriesMatchBruteForceForEveryStructure) {
    const auto ph = random_photons(50000, 1);
    const float r = 0.05f;
    PhotonMap dense(ph, r, GridKind::Hash, HashGrid::Mode::Dense);
    PhotonMap hashed(ph, r, GridKind::Hash, HashGrid::Mode::Hashed);
    PhotonMap kd(ph, r, GridKind::KdTree);
    ASSERT_TRUE(dense.grid()->dense());
    ASSERT_FALSE(hashed.grid()->dense());
    std::mt19937 rng(2);
    std::uniform_real_distribution<float> u(-1.2f, 1.2f);  // some queries outside the photons' box
    std::size_t total = 0;
    for (int i = 0; i < 300; ++i) {
        const Vec3f q{u(rng), u(rng), u(rng) * 0.3f};
        const float rq = i % 2 ? r : r * 0.6f;
        const auto ref = brute_radius(ph, q, rq);
        total += ref.size();
        expect_same_set(positions(dense, dense.query_radius(q, rq)), ref);
        expect_same_set(positions(hashed, hashed.query_radius(q, rq)), ref);
        expect_same_set(positions(kd, kd.query_radius(q, rq)), ref);
    }
    EXPECT_GT(total, 1000u);  // the queries did find photons
}

TEST(PhotonSearch, KnnMatchesBruteForce) {
    const auto ph = random_photons(5000, 3);
    const float r = 0.2f;
    PhotonMap grid(ph, r, GridKind::Hash);
    PhotonMap kd(ph, r, GridKind::KdTree);
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (int i = 0; i < 100; ++i) {
        const Vec3f q{u(rng), u(rng), u(rng) * 0.3f};
        std::vector<std::pair<float, Vec3f>> all;
        for (const auto& p : ph) {
            const float d2 = dot(p.p - q, p.p - q);
            if (d2 <= r * r) all.push_back({d2, p.p});
        }
        std::sort(all.begin(), all.end(), [](auto& a, auto& b) { return a.first < b.first; });
        const std::size_t k = 20;
        const auto g = positions(grid, grid.query_knn(q, int(k), r));
        const auto t = positions(kd, kd.query_knn(q, int(k), r));
        ASSERT_EQ(g.size(), std::min(k, all.size()));
        ASSERT_EQ(t.size(), g.size());
        for (std::size_t j = 0; j < g.size(); ++j) {  // nearest first, equal distances
            EXPECT_FLOAT_EQ(dot(g[j] - q, g[j] - q), all[j].first);
            EXPECT_FLOAT_EQ(dot(t[j] - q, t[j] - q), all[j].first);
        }
    }
}

TEST(PhotonSearch, EmptyMapFindsNothing) {
    std::vector<Photon> none;
    PhotonMap grid(none, 0.1f, GridKind::Hash);
    PhotonMap kd(none, 0.1f, GridKind::KdTree);
    EXPECT_TRUE(grid.query_radius({0, 0, 0}, 0.1f).empty());
    EXPECT_TRUE(kd.query_knn({0, 0, 0}, 3, 0.1f).empty());
}
