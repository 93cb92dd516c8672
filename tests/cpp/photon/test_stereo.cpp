// The stereo-reuse contract: a pixel the right eye reuses from the left is what the right eye
// computes for that hit point.
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>

#include "photon/gather.h"
#include "photon/renderer.h"
#include "photon/scene.h"
#include "photon/stereo.h"
#include "views/camera.h"
#include "photon/small_cornell.h"

using namespace gigascroll;

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
