// The gallery's one scene: geometry ids map to painting slots for the feedback pass, photons
// read a painting's colour at the pinned level, and the baked lattice reproduces the full
// irradiance at its points.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>
#include <cstdint>
#include <vector>

#include "cache/virtual_texture.h"
#include "common/error.h"
#include "gallery/gallery.h"
#include "pack/geometry.h"
#include "views/camera.h"

using namespace gigascroll;

namespace {

// A 2 m floor quad at y = 0 facing up, a 0.5 m light at y = 2 facing down, and one painting
// (uniform sRGB colour (200, 40, 20)) standing at z = -0.5.
struct Room {
    PackGeometry layout = PackGeometry::make(16, 2, {{64, 32}});
    VirtualTexture vt{layout, 8, 8, [](const TileKey&, std::uint8_t* out) {
                          for (std::size_t i = 0; i < 16 * 16; ++i)
                              out[3 * i] = 200, out[3 * i + 1] = 40, out[3 * i + 2] = 20;
                      }};
    Gallery gallery;
    Room() {
        const float floor[12] = {-1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1};
        const float light[12] = {-0.25f, 2, -0.25f, 0.25f, 2, -0.25f, 0.25f, 2, 0.25f, -0.25f, 2, 0.25f};
        const std::int64_t quad[6] = {0, 1, 2, 0, 2, 3};
        gallery.add_surface(floor, 4, quad, 2, {0.5f, 0.5f, 0.5f}, {0, 0, 0});
        gallery.add_surface(light, 4, quad, 2, {0, 0, 0}, {10, 10, 10});
        gallery.add_painting(0, layout.paintings[0], {-0.5, 1.0, -0.5}, {1, 0, 0}, {0, -1, 0}, 1.0, 0.5);
        gallery.commit();
    }
};

}  // namespace

TEST(Gallery, FeedbackViewMapsGeometriesToSlots) {
    Room room;
    const PaintingSceneView view = room.gallery.feedback_view();
    EXPECT_EQ(view.handle, room.gallery.scene().handle());
    ASSERT_EQ(view.paintings.size(), 1u);
    EXPECT_EQ(view.placement_of(0), -1);  // floor
    EXPECT_EQ(view.placement_of(1), -1);  // light
    EXPECT_EQ(view.placement_of(2), 0);   // the painting
    EXPECT_EQ(view.placement_of(99), -1);
    EXPECT_EQ(room.gallery.slot_of(4), 0);
    EXPECT_EQ(room.gallery.slot_of(5), 0);
    EXPECT_EQ(room.gallery.slot_of(0), -1);
}

TEST(Gallery, PhotonsReadThePaintingsColourAtThePinnedLevel) {
    Room room;
    room.gallery.light(room.vt, {});
    const Scene& scene = room.gallery.scene();
    const float expected[3] = {kPaintingReflectance * srgb_to_linear(200 / 255.0f),
                               kPaintingReflectance * srgb_to_linear(40 / 255.0f),
                               kPaintingReflectance * srgb_to_linear(20 / 255.0f)};
    const Vec3f a = scene.albedo_at(4, Vec3f(-0.2f, 0.8f, -0.5f));
    EXPECT_NEAR(a.x, expected[0], 1e-4);
    EXPECT_NEAR(a.y, expected[1], 1e-4);
    EXPECT_NEAR(a.z, expected[2], 1e-4);
    // Room surfaces keep their own albedo.
    EXPECT_EQ(scene.albedo_at(0, Vec3f(0, 0, 0)).x, 0.5f);
    const std::uint32_t level = room.gallery.stats().albedo_levels.at(0);
    EXPECT_TRUE(room.vt.is_pinned({0, level, 0, 0}));
    EXPECT_TRUE(level == 0 || !room.vt.is_pinned({0, level - 1, 0, 0}));
}

TEST(Gallery, BakedIrradianceEqualsFullAtLatticeCorners) {
    Room room;
    LightingSettings ls;
    ls.photons = 20000;
    room.gallery.light(room.vt, ls);
    BakeSettings bs;
    bs.spacing = 0.3;
    bs.light_samples = ls.light_samples;  // the same estimator as lighting "full"
    room.gallery.bake(bs);
    for (Vec3f corner : {Vec3f(-1, 0, -1), Vec3f(-1, 0, 1), Vec3f(1, 0, 1)}) {
        Hit h;
        h.tri = 0, h.p = corner, h.n = Vec3f(0, 1, 0), h.front = true;
        const Vec3f full = room.gallery.irradiance_full(h), baked = room.gallery.irradiance_baked(h);
        EXPECT_GT(full.x, 0);
        EXPECT_NEAR(baked.x, full.x, 1e-4f * full.x);
        EXPECT_NEAR(baked.z, full.z, 1e-4f * full.z);
    }
    // The floor's back side sees no light.
    Hit back;
    back.tri = 0, back.p = Vec3f(0.1f, 0, 0.2f), back.n = Vec3f(0, -1, 0), back.front = false;
    EXPECT_EQ(room.gallery.irradiance_baked(back).x, 0.0f);
}

// The display pass looks the baked lattice up at Embree's hit barycentrics instead of
// solving for them from the point: both must give the same irradiance (the old path, through
// the point, is the reference), on both sides, and the batched lookup equals the single one.
TEST(Gallery, BakedIrradianceAtEmbreeBarycentricsEqualsThePointsLookup) {
    Room room;
    LightingSettings ls;
    ls.photons = 20000;
    room.gallery.light(room.vt, ls);
    BakeSettings bs;
    bs.spacing = 0.15;
    room.gallery.bake(bs);
    const Scene& scene = room.gallery.scene();
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> coord(-0.99f, 0.99f);
    std::vector<std::uint32_t> tris;
    std::vector<bool> sides;
    std::vector<float> b1s, b2s;
    std::vector<Vec3f> singles;
    float spread = 0;
    for (int k = 0; k < 400; ++k) {
        const bool from_above = k % 2 == 0;  // the floor's front (up) and back side
        RTCRayHit rh{};
        rh.ray.org_x = coord(rng), rh.ray.org_y = from_above ? 1.0f : -1.0f, rh.ray.org_z = coord(rng);
        rh.ray.dir_x = 0, rh.ray.dir_y = from_above ? -1.0f : 1.0f, rh.ray.dir_z = 0;
        rh.ray.tnear = 0, rh.ray.tfar = 1.5f, rh.ray.mask = ~0u;  // the floor at t = 1, never the light
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        rtcIntersect1(scene.handle(), &context, &rh);
        ASSERT_NE(rh.hit.geomID, RTC_INVALID_GEOMETRY_ID);
        Hit h;
        h.tri = scene.triangle_of(rh.hit.geomID, rh.hit.primID);
        h.p = Vec3f(rh.ray.org_x, rh.ray.org_y, rh.ray.org_z) + Vec3f(rh.ray.dir_x, rh.ray.dir_y, rh.ray.dir_z) * rh.ray.tfar;
        h.front = from_above;
        h.n = from_above ? scene.normal(h.tri) : -scene.normal(h.tri);
        const Vec3f ref = room.gallery.irradiance_baked(h);
        const Vec3f got = room.gallery.irradiance_baked_at(h.tri, h.front, rh.hit.u, rh.hit.v);
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], ref[c], 2e-4f * std::max(ref[c], 1e-3f)) << k;
        spread = std::max(spread, ref.x);
        tris.push_back(h.tri), sides.push_back(h.front), b1s.push_back(rh.hit.u), b2s.push_back(rh.hit.v);
        singles.push_back(got);
    }
    EXPECT_GT(spread, 0.0f);
    std::unique_ptr<bool[]> front(new bool[sides.size()]);
    for (std::size_t k = 0; k < sides.size(); ++k) front[k] = sides[k];
    std::vector<Vec3f> batch(tris.size());
    room.gallery.irradiance_baked_batch(tris.data(), front.get(), b1s.data(), b2s.data(), tris.size(), batch.data());
    for (std::size_t k = 0; k < tris.size(); ++k)
        for (int c = 0; c < 3; ++c) EXPECT_EQ(batch[k][c], singles[k][c]) << k;
}

TEST(Gallery, RefusesBadInput) {
    Room room;
    EXPECT_THROW(room.gallery.commit(), InvalidArgument);
    Gallery dark;
    const float floor[12] = {-1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1};
    const std::int64_t quad[6] = {0, 1, 2, 0, 2, 3};
    EXPECT_THROW(dark.add_surface(floor, 4, quad, 2, {1.0f, 0.5f, 0.5f}, {0, 0, 0}), InvalidArgument);
    dark.add_surface(floor, 4, quad, 2, {0.5f, 0.5f, 0.5f}, {0, 0, 0});
    dark.commit();
    EXPECT_THROW(dark.light(room.vt, {}), InvalidArgument);  // no light
    EXPECT_THROW(dark.bake({}), InvalidArgument);             // not lit
    EXPECT_THROW(parse_lighting("sunny"), InvalidArgument);
}

TEST(Gallery, DisplayShowsAlbedoTimesIrradianceOverPiOnTwoThreads) {
    Room room;
    LightingSettings ls;
    ls.photons = 20000;
    ls.threads = 2;
    room.gallery.light(room.vt, ls);
    BakeSettings bs;
    bs.spacing = 0.25, bs.threads = 2;
    room.gallery.bake(bs);
    const Camera camera = Camera::look_at({0, 0.75, 1.5}, {0, 0.75, -0.5}, {0, 1, 0}, 50, 24, 16);
    std::vector<float> unlit(24 * 16 * 3), baked(24 * 16 * 3), E(24 * 16 * 3);
    std::vector<std::int32_t> slot(24 * 16);
    room.gallery.render_display(camera, room.vt, Lighting::Unlit, unlit.data(), {}, 2);
    DisplayHits hits;
    hits.slot = slot.data(), hits.irradiance = E.data();
    room.gallery.render_display(camera, room.vt, Lighting::Baked, baked.data(), hits, 2);
    const float red = kPaintingReflectance * srgb_to_linear(200 / 255.0f);
    int painting = 0;
    for (std::size_t i = 0; i < slot.size(); ++i) {
        if (slot[i] != 0) continue;
        ++painting;
        EXPECT_NEAR(unlit[3 * i], red, 2e-3f);
        EXPECT_NEAR(baked[3 * i], unlit[3 * i] * E[3 * i] / float(M_PI), 1e-5f + 1e-4f * baked[3 * i]);
    }
    EXPECT_GT(painting, 20);
}
