// Photon mapper: search structures against brute force, determinism, camera projection and
// the stereo-reuse contract.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "common/error.h"
#include "views/camera.h"
#include "photon/hash_grid.h"
#include "photon/kd_tree.h"
#include "photon/photon_map.h"
#include "photon/photon_tracer.h"
#include "photon/renderer.h"
#include "photon/scenes.h"
#include "photon/stereo.h"

using namespace gigascroll;

namespace {

std::vector<Photon> random_photons(std::size_t n, unsigned seed, float extent = 1.0f) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-extent, extent);
    std::vector<Photon> ph(n);
    for (auto& p : ph) {
        p.p = {u(rng), u(rng), u(rng) * 0.3f};  // clustered in z, like photons on surfaces
        p.power = {1, 1, 1};
        p.n = {0, 0, 1};
    }
    return ph;
}

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

TEST(PhotonSearch, EmptyMapFindsNothing) {
    std::vector<Photon> none;
    PhotonMap grid(none, 0.1f, GridKind::Hash);
    PhotonMap kd(none, 0.1f, GridKind::KdTree);
    EXPECT_TRUE(grid.query_radius({0, 0, 0}, 0.1f).empty());
    EXPECT_TRUE(kd.query_knn({0, 0, 0}, 3, 0.1f).empty());
}

TEST(Camera, ProjectInvertsTheRayThroughAPixel) {
    const Camera cam = Camera::look_at({0.3, 1.0, 4.0}, {0, 0, 0}, {0, 1, 0}, 45.0, 80, 60);
    for (int y = 0; y < 60; y += 7)
        for (int x = 0; x < 80; x += 9) {
            const Vec3f p = cam.ray_origin() + cam.ray_direction(float(x) + 0.5f, float(y) + 0.5f) * 3.7f;
            int px = -1, py = -1;
            ASSERT_TRUE(cam.project(p, px, py));
            EXPECT_EQ(px, x);
            EXPECT_EQ(py, y);
        }
    int px, py;
    EXPECT_FALSE(cam.project(cam.ray_origin() - Vec3f(cam.forward), px, py));  // behind the eye
}

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

// A committed Cornell box of size x size pixels and settings for a small, fast render.
struct SmallCornell {
    explicit SmallCornell(int size, std::uint64_t photons) : cam(build_cornell(scene, size, size)) {
        scene.commit();
        settings.photons = photons;
        settings.gather.radius = 0.1f;
    }
    Scene scene;
    Camera cam;
    RenderSettings settings;
};

TEST(Renderer, ImageIndependentOfThreadCountAndPipeline) {
    SmallCornell box(24, 20000);
    const Scene& scene = box.scene;
    const Camera& cam = box.cam;
    RenderSettings s = box.settings;
    s.threads = 1;
    RenderStats st;
    const auto one = Renderer(scene, s).render(cam, st);
    s.threads = 2;
    const auto two = Renderer(scene, s).render(cam, st);
    EXPECT_EQ(one, two);
    s.pipeline = Pipeline::TwoPass;
    const auto tp = Renderer(scene, s).render(cam, st);
    s.cooperative = true;
    const auto coop = Renderer(scene, s).render(cam, st);
    for (std::size_t i = 0; i < one.size(); ++i) {
        EXPECT_NEAR(tp[i], one[i], 1e-4f * (1.0f + one[i]));
        EXPECT_NEAR(coop[i], one[i], 1e-4f * (1.0f + one[i]));
    }
}

TEST(Stereo, ReusedPixelsMatchWhatTheRightEyeComputesForThatHitPoint) {
    SmallCornell box(48, 30000);
    const Scene& scene = box.scene;
    Renderer R(scene, box.settings);
    const StereoCamera eyes(box.cam, 0.1f);
    const StereoImages out = render_stereo(R, eyes, true, /*keep_sources=*/true);
    ASSERT_GT(out.right_stats.reused_pixels, 48u * 48u / 2);  // most of the view is shared
    std::size_t checked = 0, matched = 0;
    KnnHeap heap;
    ShadeCounters c;
    for (std::size_t i = 0; i < out.sources.size(); ++i) {
        const Hit& src = out.sources[i];
        if (src.t == 0) continue;
        // The right eye's own ray toward that hit point: it reaches the same triangle, from
        // the same side, within float rounding of the same point.
        Hit h;
        ASSERT_TRUE(scene.intersect(eyes.right.ray_origin(), src.p - eyes.right.ray_origin(), h));
        ASSERT_EQ(h.tri, src.tri);
        ASSERT_EQ(h.front, src.front);
        ASSERT_LT(length(h.p - src.p), 1e-4f);
        ++checked;
        // Shaded for that hit point as the right eye sees it: exactly the reused colour.
        const Hit right_hit = h;
        h.p = src.p;
        const Vec3f exact = R.surface_radiance(h, heap, c);
        const float* got = &out.right[3 * i];
        EXPECT_EQ(exact.x, got[0]);
        EXPECT_EQ(exact.y, got[1]);
        EXPECT_EQ(exact.z, got[2]);
        // With the right eye's own rounding of the point: photons exactly on the gather
        // sphere or a position-quantisation boundary may change, rarely.
        const Vec3f mine = R.surface_radiance(right_hit, heap, c);
        if (std::abs(mine.x - got[0]) <= 1e-3f * (1 + mine.x)) ++matched;
    }
    EXPECT_EQ(checked, out.right_stats.reused_pixels);
    EXPECT_GE(double(matched), 0.9 * double(checked));
}
