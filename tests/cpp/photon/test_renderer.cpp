// The renderer's image does not depend on the thread count or the pipeline.
#include <gtest/gtest.h>

#include <cstddef>

#include "photon/renderer.h"
#include "photon/small_cornell.h"

using namespace gigascroll;

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
    s.grid = GridKind::Hash;  // the cooperative gather is VR-photon-mapping's, on its grid
    s.cooperative = true;
    const auto coop = Renderer(scene, s).render(cam, st);
    for (std::size_t i = 0; i < one.size(); ++i) {
        EXPECT_NEAR(tp[i], one[i], 1e-4f * (1.0f + one[i]));
        EXPECT_NEAR(coop[i], one[i], 1e-4f * (1.0f + one[i]));
    }
}
