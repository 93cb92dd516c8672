// The Gallery's bake limit (a triangle needs at least lattice_points(gather_stride) points,
// a bake holds BakeSettings::max_points) and where it holds a room far from the origin.
#include <gtest/gtest.h>

#include <cstdint>
#include <string>

#include "cache/virtual_texture.h"
#include "common/error.h"
#include "gallery/gallery.h"
#include "pack/geometry.h"

using namespace gigascroll;

namespace {

// A 2 m floor and a 0.5 m ceiling light (4 triangles), moved by `offset`.
struct SmallRoom {
    PackGeometry layout = PackGeometry::make(16, 2, {{64, 32}});
    VirtualTexture vt{layout, 8, 8, [](const TileKey&, std::uint8_t* out) {
                          for (std::size_t i = 0; i < 3 * 16 * 16; ++i) out[i] = 128;
                      }};
    Gallery gallery;
    explicit SmallRoom(Vec3f offset = {0, 0, 0}) {
        float floor[12] = {-1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1};
        float light[12] = {-0.25f, 2, -0.25f, 0.25f, 2, -0.25f, 0.25f, 2, 0.25f, -0.25f, 2, 0.25f};
        for (int i = 0; i < 12; ++i) floor[i] += offset[i % 3], light[i] += offset[i % 3];
        const std::int64_t quad[6] = {0, 1, 2, 0, 2, 3};
        gallery.add_surface(floor, 4, quad, 2, {0.5f, 0.5f, 0.5f}, {0, 0, 0});
        gallery.add_surface(light, 4, quad, 2, {0, 0, 0}, {10, 10, 10});
        gallery.commit();
        LightingSettings ls;
        ls.photons = 2000, ls.light_samples = 256;
        gallery.light(vt, ls);
    }
};

std::string bake_error(Gallery& g, std::uint64_t max_points, int stride) {
    BakeSettings s;
    s.spacing = 100;  // one segment per edge: the fewest points a triangle can have
    s.max_points = max_points, s.gather_stride = stride, s.light_samples = 1;
    try {
        g.bake(s);
    } catch (const InvalidArgument& e) {
        return e.what();
    }
    return "";
}

}  // namespace

TEST(GalleryLimits, BakeHoldsThreePointsPerTriangleAtLeast) {
    SmallRoom room;
    // 4 triangles x 3 points (n = 1: its corners) = 12.
    EXPECT_EQ(bake_error(room.gallery, 12, 1), "");
    EXPECT_EQ(room.gallery.stats().bake_points, 12u);
    const std::string e = bake_error(room.gallery, 11, 1);
    EXPECT_NE(e.find("4 triangles are too many to bake"), std::string::npos) << e;
    EXPECT_NE(e.find("at most 3 triangles"), std::string::npos) << e;
    // gather_stride 2: n is rounded up to 2, (2 + 1)(2 + 2) / 2 = 6 points per triangle.
    EXPECT_EQ(bake_error(room.gallery, 24, 2), "");
    EXPECT_NE(bake_error(room.gallery, 23, 2).find("at least 6 lattice points"), std::string::npos);
}

TEST(GalleryLimits, RoomAroundTheOriginKeepsItsCoordinates) {
    SmallRoom room;
    EXPECT_EQ(room.gallery.origin().x, 0);
    EXPECT_EQ(room.gallery.origin().y, 0);
    EXPECT_EQ(room.gallery.origin().z, 0);
    EXPECT_EQ(room.gallery.scene().bounds_min().x, -1.0f);
}

TEST(GalleryLimits, FarRoomIsHeldAroundItselfAndLitAsAtTheOrigin) {
    const Vec3f offset(9000.0f, 5000.0f, 0.0f);
    SmallRoom far(offset), near;
    // x and y are far (one side of the origin): held around the room's middle; z spans 0.
    EXPECT_EQ(far.gallery.origin().x, 9000.0);
    EXPECT_EQ(far.gallery.origin().y, 5001.0);
    EXPECT_EQ(far.gallery.origin().z, 0.0);
    const auto [lo, hi] = far.gallery.bounds();
    EXPECT_EQ(lo.x, 8999.0);
    EXPECT_EQ(hi.y, 5002.0);
    // The irradiance on the floor: the mean over 25 points as at the origin (other samples:
    // lighting "full" seeds its emitter samples by position, 256 each here).
    double sum_near = 0, sum_far = 0;
    for (int i = 0; i < 25; ++i) {
        const Vec3d p(-0.8 + 0.4 * (i % 5), 1, -0.8 + 0.4 * (i / 5));
        Hit a, b;
        ASSERT_TRUE(near.gallery.intersect(p, Vec3f(0, -1, 0), a));
        ASSERT_TRUE(far.gallery.intersect(p + Vec3d(offset), Vec3f(0, -1, 0), b));
        EXPECT_EQ(a.tri, b.tri);
        EXPECT_NEAR(double(b.p.x) - offset.x, a.p.x, 1e-3);  // world coordinates
        EXPECT_NEAR(double(b.p.y) - offset.y, a.p.y, 1e-3);
        // irradiance_full takes the room's own coordinates (as the display pass's hits are).
        b.p = Vec3f(Vec3d(b.p) - far.gallery.origin());
        sum_near += near.gallery.irradiance_full(a).x, sum_far += far.gallery.irradiance_full(b).x;
    }
    EXPECT_NEAR(sum_far, sum_near, 0.02 * sum_near);
}
