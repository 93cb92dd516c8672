// A baked light as the display pass reads it: the lattice of irradiance points on each
// triangle (Gallery::bake) as plain arrays, and the one definition of where barycentrics fall
// on a triangle's lattice (lattice_cell), shared by the Gallery's lookups and the display
// pass's lanes (display/lattice_lanes.h).
#pragma once
#include <cstdint>

#include "common/vec3.h"

namespace gigascroll {

// Baked lighting as plain arrays, for the display pass to interpolate itself in SIMD lanes
// straight from a packet's hits (no LightQuery / SurfaceLight records, no virtual call per
// packet). The hit's triangle is t = first_triangle[geom] + prim; the side it is seen from is
// the front when the eye-facing normal agrees with normal[t]; the irradiance there is the
// linear interpolation at Embree's barycentrics on t's lattice of segments[t] segments per
// edge, whose points start at offset[t] in front (or back): Gallery::irradiance_baked_at.
// emission[t] is emitted from the front only.
struct BakedLattice {
    const std::uint32_t* first_triangle = nullptr;  // per Embree geometry
    const Vec3f *normal = nullptr, *albedo = nullptr, *emission = nullptr;  // per triangle
    const std::uint32_t* segments = nullptr;                                // per triangle
    const std::uint64_t* offset = nullptr;                                  // per triangle
    const Vec3f *front = nullptr, *back = nullptr;                          // per lattice point
    // The counts (0: unknown): when 3 x either is below 2^31 the display pass gathers the
    // arrays in 16 lanes with 32-bit indices (AVX-512), else it reads them lane by lane.
    std::uint64_t triangles = 0, points = 0;
};

// Where barycentrics (b1, b2) fall on a triangle's lattice of n segments per edge: the cell
// (i, j), whether they lie in its upper sub-triangle (i+1, j+1), (i, j+1), (i+1, j) rather than
// the lower one (i, j), (i+1, j), (i, j+1), and the weights of those three corners in that
// order. (b1, b2) are clamped onto the triangle first (Embree's u, v may round just outside);
// on the far edge, which has no upper sub-triangle, rounding can put the point just past the
// lower one, so it is scaled back onto the edge. Selects only, no branches: which sub-triangle
// a pixel falls in is a coin toss (a branch on it mispredicted half the time), and loops over
// it vectorise. The one definition of the arithmetic for the Gallery's lookups and the
// display pass (whose AVX2 and AVX-512 lanes do the same operations).
struct LatticeCell {
    std::int32_t i, j;
    bool upper;
    float w0, w1, w2;
};
[[gnu::always_inline]] inline LatticeCell lattice_cell(std::int32_t n, float b1, float b2) {
    b1 = b1 < 0.0f ? 0.0f : (1.0f < b1 ? 1.0f : b1);  // std::clamp
    b2 = b2 < 0.0f ? 0.0f : (1.0f < b2 ? 1.0f : b2);
    const float s = b1 + b2;
    const bool over = s > 1.0f;
    const float q1 = b1 / s, q2 = b2 / s;
    b1 = over ? q1 : b1, b2 = over ? q2 : b2;
    const float x = b1 * float(n), y = b2 * float(n);  // x + y <= n
    const std::int32_t xi = std::int32_t(x), yi = std::int32_t(y);
    const std::int32_t i = xi < n - 1 ? xi : n - 1;
    const std::int32_t j = yi < n - 1 - i ? yi : n - 1 - i;
    const float ex = x - float(i), ey = y - float(j);
    float fx = ex < 0.0f ? 0.0f : ex, fy = ey < 0.0f ? 0.0f : ey;
    const float sum = fx + fy;
    const bool upper = sum > 1.0f && i + j + 2 <= n;
    const bool rescale = !upper && sum > 1.0f;
    const float inv = 1.0f / sum;
    const float sx = fx * inv, sy = fy * inv;
    fx = rescale ? sx : fx, fy = rescale ? sy : fy;
    return {i, j, upper, upper ? fx + fy - 1 : 1 - fx - fy, upper ? 1 - fx : fx, upper ? 1 - fy : fy};
}

}  // namespace gigascroll
