#pragma once
// The final gather's bright spots as lights of their own.
//
// A final gather looks up a first pass's irradiance where its rays land. Where a small patch
// is far brighter than the rest of the room (the ceiling a few centimetres from a light), the
// few rays of a lattice point that happen to land on it carry most of its light: white specks
// in the bake, whatever the photon count. So the lattice points of the first pass whose
// outgoing radiance (albedo x E / pi) is above a threshold leave the gather (their value is
// zero in the lattice the rays look up) and are summed explicitly at every gather point as
// small area lights, with a shadow ray each (next-event estimation): the same light, without
// the noise. Linear interpolation makes the removed part a sum of hat functions, one per hot
// point, each of integral value x twice the lattice cell's area: the area of its light.

#include <cstdint>
#include <vector>

#include "common/vec3.h"
#include "photon/scene.h"

namespace gigascroll {

struct HotLattice {
    std::vector<Vec3f> position, normal;  // the light's centre (off the surface) and facing
    std::vector<Vec3f> power;             // radiance x area (W / sr per channel)
    std::vector<float> area;              // m^2
    std::vector<float> cdf;               // over luminance(power), for sampling when many
    bool empty() const { return position.empty(); }
};

// Finds the hot points of a first-pass lattice (front, back: per triangle from offset[t],
// n[t] segments, as Gallery::bake stores them; point positions v0 + e1 i / n + e2 j / n),
// zeroes them in front / back, and returns them as lights. Hot: luminance of albedo x E above
// `factor` times the mean over the lattice's lit point sides; at most `max_points` (the
// brightest). factor <= 0: none.
HotLattice extract_hot_points(const Scene& scene, std::vector<Vec3f>& front, std::vector<Vec3f>& back,
                              const std::vector<std::uint64_t>& offset, const std::vector<std::uint32_t>& n,
                              const std::vector<Vec3f>& v0, const std::vector<Vec3f>& e1,
                              const std::vector<Vec3f>& e2, float factor, std::size_t max_points);

// The irradiance at p (normal nrm) from the hot points: every one when there are at most
// `samples`, else `samples` of them chosen in proportion to their power by systematic
// sampling with offset u in [0, 1). Each with a shadow ray; the distance squared kept above
// the light's area (its own size: no spike beside it).
Vec3f hot_irradiance(const Scene& scene, const HotLattice& hot, Vec3f p, Vec3f nrm, int samples, double u);

}  // namespace gigascroll
