// Composition of a foveated eye (issue 14 §1, fixed foveation): the periphery, traced over
// the whole eye at `factor` times the eye's pixel pitch (a centred camera of
// ceil(width / factor) x ceil(height / factor) pixels or more), is upsampled bilinearly to
// the eye's pixels, and the fovea, traced at the eye's pitch by a centred crop camera whose
// top-left pixel is (x0, y0), is blended over it with weight weight_y[y] * weight_x[x]
// (1 inside the blend band: the fovea's pixel as traced). One pass over the eye, rows in
// parallel; the arithmetic is gigascroll.gallery.foveation's numpy reference, rows first.
#pragma once
#include <cstdint>

namespace gigascroll {

struct FoveatedEye {
    std::uint32_t width = 0, height = 0;     // the eye's pixels
    std::uint32_t factor = 2;                // periphery pitch / eye pitch
    std::uint32_t periphery_width = 0, periphery_height = 0;
    std::uint32_t x0 = 0, y0 = 0;            // the fovea's top-left pixel in the eye
    std::uint32_t fovea_width = 0, fovea_height = 0;
};

// periphery: periphery_height x periphery_width x 3; fovea: fovea_height x fovea_width x 3;
// weight_x: fovea_width, weight_y: fovea_height (in [0, 1]); out: height x width x 3.
// Sizes that do not fit (a fovea outside the eye, a periphery that does not cover it) are an
// InvalidArgument.
void composite_foveated(const FoveatedEye& eye, const float* periphery, const float* fovea,
                        const float* weight_x, const float* weight_y, float* out,
                        unsigned threads = 0);

}  // namespace gigascroll
