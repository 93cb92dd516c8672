// The display pass: a view rendered by the feedback pass (request keys, lambda and painting
// coordinates per pixel, see feedback.h) sampled through the virtual texture, as the
// seed's fragment shader samples the painting through the page table.
#pragma once
#include <cstdint>

#include "sampling/sampler.h"
#include "views/feedback.h"

namespace gigascroll {

// Samples every `step`-th pixel per axis of a width x height view: the painting named by
// the pixel's key at (u, v), bilinear at the level round(lambda) (falling back to the
// finest resident ancestor like any lookup). Pixels without a painting are black. keys is
// the full width x height buffer; lod, uv and out are on the display grid of
// ceil(height / step) x ceil(width / step) pixels (render_view with display_step =
// step); out holds 3 floats in 0..255 per pixel, row-major.
void display_view(const VirtualTexture& vt, const std::uint64_t* keys, const float* lod,
                  const double* uv, std::uint32_t width, std::uint32_t height,
                  std::uint32_t step, float* out, unsigned threads = 0);

}  // namespace gigascroll
