// The feedback pass against analytic footprints (head-on and grazing), lod bias, the display
// grid, the tile under every pixel, occluders and misses.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/error.h"
#include "pack/geometry.h"
#include "pack/tile_key.h"
#include "views/camera.h"
#include "views/exhibition.h"
#include "views/feedback.h"
#include "support/feedback_image.h"

using namespace gigascroll;

namespace {
// A wall painting facing -z with texel (0,0) at (0, 1, 0), like the scroll.
struct WallScene {
    ExhibitionScene scene;
    PaintingGeometry tiles{152089, 6083};
    WallScene() {
        scene.add_painting(0, tiles, {0, 1.75, 0}, {1, 0, 0}, {0, -1, 0}, 12.0, 0.5);
        scene.add_box({-1, 0, 0.01}, {13, 3, 0.2});
        scene.commit();
    }
};
const double kTexel = 12.0 / 152089;
const double kTanHalf = 900 * kTexel / 0.072;  // the Quest Pro assumption of views.py
}  // namespace

TEST(Feedback, HeadOnLevelMatchesAnalyticFootprint) {
    WallScene w;
    for (double d : {0.05, 0.072, 0.1, 0.25, 0.4, 1.0, 3.0}) {
        const Camera cam({6, 1.5, -d}, {0, 0, 1}, {0, 1, 0}, kTanHalf, kTanHalf * 1920 / 1800, 1800,
                         1920);
        // Analytic: a display pixel spans 2 tan(fov/2) / W radians on the axis, d times that
        // in metres, over the texel size; head-on the footprint is the same everywhere.
        const double rho = d * 2 * kTanHalf / 1800 / kTexel;
        FeedbackOptions o{45, 48, 0, 2};
        std::vector<std::uint64_t> keys(45 * 48);
        std::vector<float> lod(keys.size());
        render_feedback(w.scene, cam, o, keys.data(), lod.data());
        int seen = 0;
        for (std::size_t i = 0; i < keys.size(); ++i) {
            if (keys[i] == kNoRequest) continue;
            ++seen;
            EXPECT_NEAR(lod[i], std::log2(rho), 1e-4) << "d=" << d;
            const std::uint32_t expect = rho <= 1 ? 0 : std::uint32_t(std::floor(std::log2(rho)));
            EXPECT_EQ(request_level(keys[i]), std::min(expect, 11u)) << "d=" << d;
        }
        EXPECT_GT(seen, 0);
    }
    // The seed's set-up: 40 cm asks level 2, 25 cm level 1; level 0 (rho <= 1) at 7.2 cm.
    EXPECT_EQ(std::floor(std::log2(0.4 * 2 * kTanHalf / 1800 / kTexel)), 2);
    EXPECT_EQ(std::floor(std::log2(0.25 * 2 * kTanHalf / 1800 / kTexel)), 1);
}

TEST(Feedback, GrazingLevelMatchesAnalyticFootprint) {
    WallScene w;
    const double d = 0.5;  // perpendicular distance to the wall
    for (double deg : {0.0, 30.0, 60.0, 75.0, 85.0}) {
        const double th = deg * M_PI / 180;
        // Looking at (6, 1.5, 0) from a point rotated by th about the vertical.
        const Vec3d target{6, 1.5, 0}, pos{6 - d * std::tan(th), 1.5, -d};
        const Camera cam(pos, target - pos, {0, 1, 0}, kTanHalf, kTanHalf, 1800, 1800);
        // Centre pixel: the ray travels t = d / cos th; a pixel step along the tilt stretches
        // by 1 / cos th on the wall, the vertical step does not.
        const double pitch = 2 * kTanHalf / 1800, t = d / std::cos(th);
        const double rho = std::max(t * pitch / std::cos(th), t * pitch) / kTexel;
        const std::uint32_t W = 61;  // odd: the middle feedback pixel is the display centre
        FeedbackOptions o{W, W, 0, 2};
        std::vector<std::uint64_t> keys(W * W);
        std::vector<float> lod(keys.size());
        render_feedback(w.scene, cam, o, keys.data(), lod.data());
        const std::size_t centre = (W / 2) * W + W / 2;
        ASSERT_NE(keys[centre], kNoRequest);
        EXPECT_NEAR(lod[centre], std::log2(rho), 1e-4) << deg;
        EXPECT_EQ(request_level(keys[centre]), mip_level(std::log2(rho), 12)) << deg;
        EXPECT_NEAR(texel_footprint(w.scene.paintings()[0], cam, cam.direction(900, 900), t), rho,
                    1e-9 * rho);
        // The tile holds the texel the centre ray hits: x = 6 m.
        const TileKey r = unpack_request(keys[centre]);
        EXPECT_EQ(r.tx, std::uint32_t(6.0 / kTexel / (120.0 * (1 << r.level))));
    }
}

TEST(Feedback, LodBiasAndDisplayGrid) {
    WallScene w;
    const double d = 0.4;
    const Camera cam({6, 1.5, -d}, {0.1, 0.05, 1}, {0, 1, 0}, kTanHalf, kTanHalf * 1920 / 1800,
                     1800, 1920);
    const std::uint32_t W = 45, H = 48;
    std::vector<std::uint64_t> keys(W * H), keys_b(W * H), keys_s(W * H);
    std::vector<float> lod(W * H), lod_b(W * H);
    std::vector<double> uv(2 * W * H);
    render_feedback(w.scene, cam, {W, H, 0, 2}, keys.data(), lod.data(), uv.data());
    // A bias shifts lambda and the level by the same amount (textureQueryLod with bias).
    render_feedback(w.scene, cam, {W, H, 0.7, 2}, keys_b.data(), lod_b.data());
    int seen = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        if (keys[i] == kNoRequest) {
            EXPECT_EQ(keys_b[i], kNoRequest);
            continue;
        }
        ++seen;
        EXPECT_NEAR(lod_b[i], lod[i] + 0.7f, 1e-5);
        EXPECT_EQ(request_level(keys_b[i]), mip_level(double(lod[i]) + 0.7, 12));
    }
    EXPECT_GT(seen, 100);
    // On a display grid of step 3, lod and uv are the full buffers' every third pixel of
    // every third row; the keys do not change.
    const std::uint32_t S = 3, DW = (W + S - 1) / S, DH = (H + S - 1) / S;
    std::vector<float> lod_s(DW * DH);
    std::vector<double> uv_s(2 * DW * DH);
    FeedbackOptions o{W, H, 0, 2, S};
    render_feedback(w.scene, cam, o, keys_s.data(), lod_s.data(), uv_s.data());
    EXPECT_EQ(keys_s, keys);
    for (std::uint32_t y = 0; y < DH; ++y)
        for (std::uint32_t x = 0; x < DW; ++x) {
            const std::size_t full = std::size_t(y * S) * W + x * S, sub = std::size_t(y) * DW + x;
            if (std::isnan(lod[full])) {
                EXPECT_TRUE(std::isnan(lod_s[sub]));
                continue;
            }
            EXPECT_EQ(lod_s[sub], lod[full]);
            EXPECT_EQ(uv_s[2 * sub], uv[2 * full]);
            EXPECT_EQ(uv_s[2 * sub + 1], uv[2 * full + 1]);
        }
    o.display_step = 0;
    EXPECT_THROW(render_feedback(w.scene, cam, o, keys_s.data()), InvalidArgument);
}

TEST(Feedback, KeysMatchTheTileUnderEveryPixel) {
    // A small painting seen whole, edges and all, at an angle: every key's tile is the one
    // holding the pixel's texel at the key's level (the last tile of a row or column reaches
    // the painting's edge), recomputed here from the uv output.
    const PaintingGeometry tiles(1000, 700);
    const PaintingOnWall wall(tiles);
    const Camera cam({0.3, 0.6, -1.2}, {0.15, -0.05, 1}, {0, 1, 0}, 0.6, 0.6, 1600, 1600);
    const std::uint32_t W = 200, H = 200;
    const auto [keys, lod, uv] = feedback_image(wall.scene, cam, W, H);
    int seen = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        if (keys[i] == kNoRequest) continue;
        ++seen;
        const TileKey r = unpack_request(keys[i]);
        const double span = 120.0 * (1 << r.level);
        const double x = uv[2 * i] * 1000, y = uv[2 * i + 1] * 700;
        auto tile = [&](double t, std::uint32_t n) {
            return std::min<std::uint32_t>(std::uint32_t(t / span), n - 1);
        };
        const bool near_edge = std::abs(x / span - std::round(x / span)) < 1e-6 ||
                               std::abs(y / span - std::round(y / span)) < 1e-6;
        if (near_edge) continue;
        EXPECT_EQ(r.tx, tile(x, tiles.tiles_x(r.level))) << i;
        EXPECT_EQ(r.ty, tile(y, tiles.tiles_y(r.level))) << i;
    }
    EXPECT_GT(seen, 5000);
    EXPECT_LT(seen, int(W * H));  // the painting's surroundings are seen too
}

TEST(Feedback, OccludersAndMissesGiveNoRequest) {
    ExhibitionScene scene;
    const PaintingGeometry tiles(1000, 1000);
    scene.add_painting(0, tiles, {0, 1, 0}, {1, 0, 0}, {0, -1, 0}, 1, 1);
    scene.add_box({-0.1, -0.1, -0.5}, {1.1, 1.1, -0.4});  // a box hiding the painting
    scene.commit();
    const Camera cam({0.5, 0.5, -1}, {0, 0, 1}, {0, 1, 0}, 1, 1, 64, 64);
    std::vector<std::uint64_t> keys(8 * 8);
    render_feedback(scene, cam, {}, keys.data());
    for (auto k : keys) EXPECT_EQ(k, kNoRequest);
    ExhibitionScene open;
    EXPECT_THROW(render_feedback(open, cam, {}, keys.data()), InvalidArgument);
    EXPECT_THROW(Camera({0, 0, NAN}, {0, 0, 1}, {0, 1, 0}, 1, 1, 8, 8), InvalidArgument);
    EXPECT_THROW(Camera({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 1, 1, 8, 8), InvalidArgument);
    EXPECT_THROW(open.add_painting(0, tiles, {0, 0, 0}, {1, 0, 0}, {1, 0, 0}, 1, 1), InvalidArgument);
}
