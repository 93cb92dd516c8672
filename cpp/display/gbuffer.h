// What the display pass keeps per pixel of a frame: the hit (for DisplayPass::hit_points and
// the right eye's reused pixels), the level, and for the left eye what a reused right pixel
// needs (its light).
#pragma once
#include <cstdint>
#include <vector>

#include "common/vec3.h"

namespace gigascroll {
namespace display {

struct GBuffer {
    std::uint32_t width = 0, height = 0;
    std::vector<unsigned> geom;        // RTC_INVALID_GEOMETRY_ID: no hit
    std::vector<Vec3f> p;
    std::vector<float> lod;            // NaN off paintings
    // Left eye only (keep_light): per painting pixel its light, radiance = linear albedo x
    // scale + add (a reused right pixel whose level differs samples its own texel under
    // the left light; one whose level agrees copies the left radiance).
    std::vector<Vec3f> scale, add;
    void resize(std::uint32_t w, std::uint32_t h, bool keep_light) {
        width = w, height = h;
        const std::size_t n = std::size_t(w) * h;
        geom.resize(n), p.resize(n), lod.resize(n);
        if (keep_light) scale.resize(n), add.resize(n);
    }
};

}  // namespace display
}  // namespace gigascroll
