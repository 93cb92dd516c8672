// Stereo reuse (VR-photon-mapping §3.3). While the left eye renders, each hit point that the right eye
// can see (an occlusion ray toward it, and the same side of the surface) is projected into the
// right image with eqs. (3)-(5); the first left sample to claim a right pixel writes its colour
// there, claimed by an atomic compare-and-swap. The right eye then computes only the pixels
// nobody claimed. Valid because every surface is Lambertian and the shading samples are seeded
// by hit position: the reused colour is the one the right eye would compute for that point.
#pragma once
#include <vector>

#include "photon/renderer.h"

namespace gigascroll {

struct StereoImages {
    std::vector<float> left, right;  // (height, width, 3) each
    RenderStats left_stats, right_stats;
    double total_seconds = 0;         // both eyes, photon pass once
    std::vector<Hit> sources;         // per right pixel: the reused left hit (t = 0: none)
};

// reuse = false renders the two eyes independently (the baseline of VR-photon-mapping Table 5).
StereoImages render_stereo(const Renderer& renderer, const StereoCamera& eyes, bool reuse,
                           bool keep_sources = false);

}  // namespace gigascroll
