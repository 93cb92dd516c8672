// The feedback pass (tile determination): rays through a view at reduced resolution find,
// per feedback pixel, the painting texel seen and the mip level a GPU's textureQueryLod
// would pick for a display pixel there, and write the request key (pack/tile_key.h).
#pragma once
#include <cstdint>

#include "views/exhibition.h"
#include "views/camera.h"

namespace gigascroll {

struct FeedbackOptions {
    std::uint32_t width = 0, height = 0;  // feedback resolution; 0 = 1/8 of the display per axis
    double lod_bias = 0;                  // added to the level of detail before truncation
    unsigned threads = 0;                 // 0 = all cores
    // lod and uv are written for every display_step-th pixel of every display_step-th row
    // only (what a display pass at that step reads), as ceil(h / step) x ceil(w / step).
    std::uint32_t display_step = 1;
};

// The footprint of a display pixel on a painting, in level-0 texels, from ray differentials
// (Igehy 1999) transferred to the painting plane: the largest of |d(u,v)/dx| and |d(u,v)/dy|,
// as in the OpenGL specification of the level of detail. lambda = log2(rho).
double texel_footprint(const PaintingPlacement& painting, const Camera& camera, Vec3d direction,
                       double t);
// The same for display pixel (px, py): the ray through it meets the painting's plane at t.
double texel_footprint_at_pixel(const PaintingPlacement& painting, const Camera& camera,
                                double px, double py);

// The level textureQueryLod(...).y truncated to an integer, as Vulkan-SVT's shader does:
// clamp(floor(lambda + bias), 0, levels - 1).
std::uint32_t mip_level(double lambda, std::uint32_t levels);

// Fills keys[height * width] (row-major) with request keys, kNoRequest where no painting is
// seen; lod (optional) receives lambda (NaN where no painting), uv (optional, 2 per pixel)
// the painting coordinates in [0, 1] that the display pass samples, both on the display
// grid (FeedbackOptions::display_step; the full resolution by default). Casts Embree
// packets of 16 rays along each row, rows shared among `threads` threads.
void render_view(const ExhibitionScene& scene, const Camera& camera,
                     const FeedbackOptions& options, std::uint64_t* keys, float* lod = nullptr,
                     double* uv = nullptr);
// The same on any scene holding paintings (a committed BVH), e.g. a Gallery's.
void render_view(const PaintingSceneView& scene, const Camera& camera,
                 const FeedbackOptions& options, std::uint64_t* keys, float* lod = nullptr,
                 double* uv = nullptr);

// Samples of an axis of n pixels on the display grid of step `step`: ceil(n / step).
inline std::uint32_t display_extent(std::uint32_t n, std::uint32_t step) {
    return (n + step - 1) / step;
}

// Largest feedback pass: 2^26 pixels (8192 x 8192; 1.75 GiB of keys, lod and uv). Throws
// InvalidArgument with the memory a larger one would need.
inline constexpr std::uint64_t kMaxFeedbackPixels = std::uint64_t(1) << 26;
void require_feedback_size(std::uint64_t width, std::uint64_t height);

// Resolved feedback resolution for a camera (applies the 1/8 default).
std::uint32_t feedback_width(const Camera& camera, const FeedbackOptions& options);
std::uint32_t feedback_height(const Camera& camera, const FeedbackOptions& options);

// Options from a caller's untrusted integers (resolution in [0, 2^16) a side, 0 = the 1/8
// default; display_step in [1, 2^16)): InvalidArgument otherwise.
FeedbackOptions checked_feedback_options(std::int64_t width, std::int64_t height, double lod_bias,
                                         unsigned threads, std::int64_t display_step);
// What a feedback pass of `camera` writes: keys (height x width) and lod/uv on the display grid
// (display_height x display_width). require_feedback_size applies: callers allocate from it.
struct FeedbackShape {
    std::uint32_t width, height, display_width, display_height;
};
FeedbackShape feedback_shape(const Camera& camera, const FeedbackOptions& options);

}  // namespace gigascroll
