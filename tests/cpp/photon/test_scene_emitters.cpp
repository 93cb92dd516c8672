// Scene::sample_emitter's emitter choice (a branch-free count for a few emitters, a guide
// table for many) against the cumulative distribution the test computes itself: u in the
// k-th of n equal-power strata picks the k-th emitter, and nothing breaks for u outside [0, 1);
// and shadow rays in packets (Scene::occluded16) against single ones.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "common/error.h"
#include "photon/scene.h"

using namespace gigascroll;

namespace {

// n unit squares (2 n triangles of equal area) emitting `radiance`, side by side along x.
void add_lights(Scene& scene, int n, float radiance) {
    std::vector<float> v;
    std::vector<std::int64_t> t;
    for (int k = 0; k < n; ++k) {
        const float x = 2.0f * float(k);
        const float quad[12] = {x, 2, 0, x + 1, 2, 0, x + 1, 2, 1, x, 2, 1};
        const std::int64_t base = std::int64_t(v.size() / 3);
        v.insert(v.end(), quad, quad + 12);
        for (std::int64_t i : {0, 1, 2, 0, 2, 3}) t.push_back(base + i);
    }
    const float albedo[3] = {0.5f, 0.5f, 0.5f};
    scene.add_mesh(v.data(), v.size() / 3, t.data(), t.size() / 3, albedo, false, {radiance, radiance, radiance});
}

}  // namespace

TEST(SceneEmitters, StrataPickTheirEmitterWithFewAndManyEmitters) {
    for (int quads : {1, 3, 8, 9, 20, 300}) {  // 2 .. 600 triangles: both sides of 16
        Scene scene;
        add_lights(scene, quads, 1.0f);
        scene.commit();
        const int n = 2 * quads;
        ASSERT_EQ(scene.emitter_count(), std::size_t(n));
        for (int k = 0; k < n; ++k)
            for (double f : {0.001, 0.5, 0.999}) {
                const float u = float((k + f) / n);
                EXPECT_EQ(scene.sample_emitter(u, 0.2f, 0.3f).tri, std::uint32_t(k)) << quads << " " << u;
            }
        // Out of range or NaN: still an emitter, as the binary search gave (the last one).
        for (float u : {-1.0f, 1.0f, 2.0f, std::numeric_limits<float>::quiet_NaN()}) {
            const LightSample s = scene.sample_emitter(u, 0.2f, 0.3f);
            EXPECT_LT(s.tri, std::uint32_t(n));
            if (!(u < 0)) EXPECT_EQ(s.tri, std::uint32_t(n - 1)) << u;
        }
    }
}

TEST(SceneEmitters, UnequalPowersTakeTheirShareOfU) {
    // Two groups: 10 weak quads and 10 four times as bright (40 triangles, the guide table):
    // the weak ones share 1/5 of [0, 1).
    Scene scene;
    add_lights(scene, 10, 1.0f);
    add_lights(scene, 10, 4.0f);
    scene.commit();
    int weak = 0;
    const int m = 100000;
    for (int i = 0; i < m; ++i) weak += scene.sample_emitter((i + 0.5f) / m, 0.1f, 0.1f).tri < 20;
    EXPECT_NEAR(double(weak) / m, 0.2, 2.0 / m);
}

// Shadow rays in one packet give the single rays' answers: random segments among a few
// quads, 1 to 16 at a time.
TEST(SceneEmitters, PacketShadowRaysAnswerAsSingleOnes) {
    Scene scene;
    add_lights(scene, 5, 1.0f);
    const float floor[12] = {-1, 0, -1, 10, 0, -1, 10, 0, 2, -1, 0, 2};
    const std::int64_t quad[6] = {0, 1, 2, 0, 2, 3};
    const float albedo[3] = {0.5f, 0.5f, 0.5f};
    scene.add_mesh(floor, 4, quad, 2, albedo, false, {0, 0, 0});
    scene.commit();
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1.5f, 11.0f), h(-0.5f, 3.0f);
    int blocked_total = 0, rays = 0;
    for (int round = 0; round < 400; ++round) {
        const int count = 1 + round % 16;
        Vec3f o[16], d[16];
        float tfar[16];
        for (int k = 0; k < count; ++k) {
            o[k] = Vec3f(u(rng), h(rng), 0.3f * u(rng));
            d[k] = Vec3f(u(rng), h(rng), 0.3f * u(rng)) - o[k];
            tfar[k] = k % 3 == 0 ? 0.5f : 1.0f;
        }
        bool out[16];
        scene.occluded16(count, o, d, tfar, out);
        for (int k = 0; k < count; ++k) {
            EXPECT_EQ(out[k], scene.occluded(o[k], d[k], tfar[k])) << round << " " << k;
            blocked_total += out[k], ++rays;
        }
    }
    EXPECT_GT(blocked_total, rays / 10);  // both answers occur
    EXPECT_LT(blocked_total, rays - rays / 10);
    // A bad ray is refused, as by occluded().
    Vec3f o[1] = {Vec3f(0, 1, 0)}, d[1] = {Vec3f(0, 0, 0)};
    float t[1] = {1};
    bool out[1];
    EXPECT_THROW(scene.occluded16(1, o, d, t, out), InvalidArgument);
}
