// What the feedback tests look at: one painting, 1 m x 0.7 m, texel (0, 0) at (0, 1, 0),
// facing -z; and a feedback pass's whole output at full resolution (display step 1).
#pragma once
#include <cstdint>
#include <vector>

#include "views/feedback.h"

namespace gigascroll {

struct PaintingOnWall {
    ExhibitionScene scene;
    explicit PaintingOnWall(const PaintingGeometry& tiles) {
        scene.add_painting(0, tiles, {0, 1, 0}, {1, 0, 0}, {0, -1, 0}, 1.0, 0.7);
        scene.commit();
    }
};

struct FeedbackImage {
    std::vector<std::uint64_t> keys;
    std::vector<float> lod;
    std::vector<double> uv;  // (u, v) per pixel
};

inline FeedbackImage feedback_image(const ExhibitionScene& scene, const Camera& camera,
                                    std::uint32_t width, std::uint32_t height, unsigned threads = 2) {
    const std::size_t n = std::size_t(width) * height;
    FeedbackImage f{std::vector<std::uint64_t>(n), std::vector<float>(n), std::vector<double>(2 * n)};
    render_feedback(scene, camera, {width, height, 0, threads}, f.keys.data(), f.lod.data(),
                    f.uv.data());
    return f;
}

}  // namespace gigascroll
