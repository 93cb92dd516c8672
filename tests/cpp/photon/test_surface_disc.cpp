// The surface disc: sector lookup against atan2, and the clipped area against geometry with
// known answers (open floor, floor against a wall, the floor's own border).
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "photon/surface_disc.h"

using namespace gigascroll;

TEST(SurfaceDisc, SectorIsTheSixteenthOfTheAngle) {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1, 1);
    for (int i = 0; i < 10000; ++i) {
        const float x = u(rng), y = u(rng);
        float a = std::atan2(y, x);
        if (a < 0) a += 2 * float(M_PI);
        const int expected = std::min(SurfaceDisc::kSectors - 1, int(a / (2 * float(M_PI) / SurfaceDisc::kSectors)));
        ASSERT_EQ(SurfaceDisc::sector(x, y), expected) << x << " " << y;
    }
}

namespace {
// A floor [-1, 1]^2 at y = 0 (normal +y) and a wall x = 0.5 standing on it.
void floor_and_wall(Scene& s) {
    const float floor_v[] = {-1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1};
    const float wall_v[] = {0.5f, 0, -1, 0.5f, 1, -1, 0.5f, 1, 1, 0.5f, 0, 1};
    const std::int64_t quad[] = {0, 1, 2, 2, 3, 0};
    const float albedo[] = {0.5f, 0.5f, 0.5f};
    s.add_mesh(floor_v, 4, quad, 2, albedo, false, {0, 0, 0});
    s.add_mesh(wall_v, 4, quad, 2, albedo, false, {0, 0, 0});
    s.commit();
}
}  // namespace

TEST(SurfaceDisc, AreaIsTheFullDiscOnOpenFloorAndHalfAtAWallOrBorder) {
    Scene s;
    floor_and_wall(s);
    const float r = 0.1f, full = float(M_PI) * r * r;
    const Vec3f up{0, 1, 0};
    EXPECT_NEAR(make_surface_disc(s, {0, 0, 0}, up, r).area / full, 1.0, 1e-4);
    // Against the wall (in-plane rays stop there) and at the floor's border x = -1 (probes
    // find no surface): about half the disc. Octant sampling is coarse: within 15%.
    EXPECT_NEAR(make_surface_disc(s, {0.495f, 0, 0}, up, r).area / full, 0.5, 0.075);
    EXPECT_NEAR(make_surface_disc(s, {-0.995f, 0, 0}, up, r).area / full, 0.5, 0.075);
    // A photon beyond the wall, coplanar with the floor, is outside the disc at the wall's foot;
    // one just off the plane by more than the tolerance too.
    const SurfaceDisc d = make_surface_disc(s, {0.45f, 0, 0}, up, r);
    EXPECT_TRUE(d.contains({0.40f, 0, 0.02f}));
    EXPECT_FALSE(d.contains({0.52f, 0, 0.0f}));
    EXPECT_FALSE(d.contains({0.40f, 0.02f, 0.0f}));
}

TEST(SurfaceDisc, APlateOverTheFloorCoversItAndCapsTheRadius) {
    // A floor [-1, 1]^2 at y = 0 and a plate 2 cm above it over x > 0.5 (a painting off its
    // wall): in-plane rays pass under the plate, the probes find it overhead. At 1 cm from its
    // rim the disc keeps nothing under the plate and shrinks to about twice that distance
    // (at least r / 8); far from the plate it stays whole.
    Scene s;
    const float floor_v[] = {-1, 0, -1, -1, 0, 1, 1, 0, 1, 1, 0, -1};
    const float plate_v[] = {0.5f, 0.02f, -1, 0.5f, 0.02f, 1, 1, 0.02f, 1, 1, 0.02f, -1};
    const std::int64_t quad[] = {0, 1, 2, 2, 3, 0};
    const float albedo[] = {0.5f, 0.5f, 0.5f};
    s.add_mesh(floor_v, 4, quad, 2, albedo, false, {0, 0, 0});
    s.add_mesh(plate_v, 4, quad, 2, albedo, false, {0, 0, 0});
    s.commit();
    const float r = 0.2f, full = float(M_PI) * r * r;
    const Vec3f up{0, 1, 0};
    const SurfaceDisc near = make_surface_disc(s, {0.49f, 0, 0}, up, r);
    EXPECT_FALSE(near.contains({0.52f, 0, 0}));   // under the plate
    EXPECT_FALSE(near.contains({0.49f, 0, 0.1f}));  // beyond the cap, along the rim
    EXPECT_TRUE(near.contains({0.48f, 0, 0.005f}));
    EXPECT_LT(near.area, float(M_PI) * 0.05f * 0.05f);  // capped near max(2 * 1 cm, r / 8) = 2.5 cm
    EXPECT_GT(near.area, 0.2f * float(M_PI) * 0.025f * 0.025f);
    EXPECT_NEAR(make_surface_disc(s, {-0.5f, 0, 0}, up, r).area / full, 1.0, 1e-4);
}

TEST(SurfaceDisc, CoarseDiscClipsLikeTheFineOneWithinItsOctants) {
    // The coarse disc (8 sectors, fewer probes) of a progressive render's first passes: the
    // same half disc at the wall and at the floor's border (within its coarser 25%), the same
    // whole disc in the open, and the same photons rejected beyond the wall.
    Scene s;
    floor_and_wall(s);
    const float r = 0.1f, full = float(M_PI) * r * r;
    const Vec3f up{0, 1, 0};
    constexpr auto coarse = SurfaceDisc::Detail::Coarse;
    EXPECT_NEAR(make_surface_disc(s, {0, 0, 0}, up, r, coarse).area / full, 1.0, 1e-4);
    EXPECT_NEAR(make_surface_disc(s, {0.495f, 0, 0}, up, r, coarse).area / full, 0.5, 0.125);
    EXPECT_NEAR(make_surface_disc(s, {-0.995f, 0, 0}, up, r, coarse).area / full, 0.5, 0.125);
    const SurfaceDisc d = make_surface_disc(s, {0.45f, 0, 0}, up, r, coarse);
    EXPECT_TRUE(d.contains({0.40f, 0, 0.02f}));
    EXPECT_FALSE(d.contains({0.52f, 0, 0.0f}));
    // Both halves of an octant share its reach.
    for (int k = 0; k < SurfaceDisc::kSectors; k += 2) EXPECT_EQ(d.reach2[k], d.reach2[k + 1]);
}
