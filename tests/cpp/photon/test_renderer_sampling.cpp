// The renderer's samples: camera samples of spp > 1 on one stratified pattern for the whole
// image, and stratified emitter samples, against Lambert's polygon formula.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "photon/polygon_irradiance.h"
#include "photon/renderer.h"
#include "photon/small_cornell.h"

using namespace gigascroll;

TEST(RendererSampling, CameraSamplesShareOneStratifiedPatternPerImage) {
    SmallCornell box(16, 1000);
    RenderSettings s = box.settings;
    s.indirect = false;
    for (int spp : {4, 16}) {
        s.spp = spp;
        const Renderer r(box.scene, s);
        std::vector<float> first(2 * spp);
        for (int y = 0; y < 5; ++y)
            for (int x = 0; x < 7; ++x) {
                Rng rng = r.pixel_rng(x, y, 0);
                for (int k = 0; k < spp; ++k) {
                    float px, py;
                    r.film_sample(x, y, k, rng, px, py);
                    ASSERT_GE(px, float(x));
                    ASSERT_LT(px, float(x + 1));
                    ASSERT_GE(py, float(y));
                    ASSERT_LT(py, float(y + 1));
                    if (x == 0 && y == 0) first[2 * k] = px, first[2 * k + 1] = py;
                    // the same offsets in every pixel: a straight edge is covered alike
                    EXPECT_NEAR(px - float(x), first[2 * k], 1e-5f);
                    EXPECT_NEAR(py - float(y), first[2 * k + 1], 1e-5f);
                }
            }
        // stratified: each half of the pixel, across and down, holds a share of the samples
        int left = 0, top = 0;
        for (int k = 0; k < spp; ++k) left += first[2 * k] < 0.5f, top += first[2 * k + 1] < 0.5f;
        EXPECT_GE(left, spp / 4);
        EXPECT_LE(left, spp - spp / 4);
        EXPECT_GE(top, spp / 4);
        EXPECT_LE(top, spp - spp / 4);
    }
    // One sample: jittered per pixel, as before.
    s.spp = 1;
    const Renderer r(box.scene, s);
    Rng a = r.pixel_rng(0, 0, 0), b = r.pixel_rng(1, 0, 0);
    float ax, ay, bx, by;
    r.film_sample(0, 0, 0, a, ax, ay);
    r.film_sample(1, 0, 0, b, bx, by);
    EXPECT_NE(ax, bx - 1.0f);
}

TEST(RendererSampling, StratifiedEmitterSamplesAreUnbiasedAndLessNoisy) {
    // The tall block's front face sees half of the light behind its plane, at grazing angles:
    // independent samples gave salt-and-pepper there. Its upper half (nothing in between) against
    // the polygon formula over the light's two triangles.
    SmallCornell box(128, 1000);
    RenderSettings s = box.settings;
    s.indirect = false;
    const Renderer r(box.scene, s);
    const Vec3f a(-0.23f, 0.99f, -0.18f), b(0.23f, 0.99f, -0.18f), c(0.23f, 0.99f, 0.2f), d(-0.23f, 0.99f, 0.2f);
    const float radiance = 18.387f;
    double sum_s = 0, sum_i = 0, sum_e = 0, se_s = 0, se_i = 0, sum_many = 0;
    int count = 0;
    for (int y = 0; y < 128; ++y)
        for (int x = 0; x < 128; ++x) {
            Hit h;
            if (!box.scene.intersect_camera(box.cam.ray_origin(), box.cam.ray_direction(x + 0.5f, y + 0.5f), h))
                continue;
            if (h.tri != 20 && h.tri != 21) continue;  // the tall block's front
            if (h.p.y < 0.0f) continue;
            const double exact = radiance * (unit_triangle_irradiance(h.p, h.n, a, b, c) +
                                             unit_triangle_irradiance(h.p, h.n, a, c, d));
            ShadeCounters cs;  // (the same per-position samples both ways)
            const double es = r.direct_irradiance(h, 16, cs, 0, true).x;
            const double ei = r.direct_irradiance(h, 16, cs, 0, false).x;
            sum_s += es, sum_i += ei, sum_e += exact;
            sum_many += r.direct_irradiance(h, 1024, cs, 0, true).x;
            se_s += (es - exact) * (es - exact) / (exact * exact);
            se_i += (ei - exact) * (ei - exact) / (exact * exact);
            ++count;
        }
    ASSERT_GT(count, 200);
    std::printf("%d points: mean / exact %.5f (1024 stratified), %.5f (16), %.5f (16 independent); "
                "relMSE %.4g stratified, %.4g independent\n", count, sum_many / sum_e, sum_s / sum_e,
                sum_i / sum_e, se_s / count, se_i / count);
    // Unbiased: many samples converge on the formula, and 16 of each kind are near it.
    EXPECT_NEAR(sum_many / sum_e, 1.0, 0.002);
    EXPECT_NEAR(sum_s / sum_e, 1.0, 0.02);
    EXPECT_NEAR(sum_i / sum_e, 1.0, 0.02);
    EXPECT_LT(se_s / count, 0.3 * se_i / count);
}
