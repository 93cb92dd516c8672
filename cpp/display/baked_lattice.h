// A baked light as the display pass reads it: the lattice of irradiance points on each
// triangle (Gallery::bake) as plain arrays, and the one definition of where barycentrics fall
// on a triangle's lattice (lattice_cell), shared by the Gallery's lookups and the display
// pass's lanes (display/lattice_lanes.h).
#pragma once
#include <cstdint>

#include "common/lanes.h"
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
// display pass's lanes at every width (lattice_cell_lanes; lattice_cell is its W = 1).
template <int W>
struct LatticeCellLanes {
    typename Lanes<W>::I i, j;
    typename Lanes<W>::M upper;
    typename Lanes<W>::F w0, w1, w2;
};
// W lanes' cells (common/lanes.h). The rare steps (a point past the far edge) are taken only
// when a lane needs them at W > 1; at W = 1 they are selects, as above.
template <int W>
[[gnu::always_inline]] inline LatticeCellLanes<W> lattice_cell_lanes(typename Lanes<W>::I n,
                                                                     typename Lanes<W>::F b1,
                                                                     typename Lanes<W>::F b2) {
    using L = Lanes<W>;
    using F = typename L::F;
    using I = typename L::I;
    const F zero(0.0f), one(1.0f);
    b1 = L::select(b1 < zero, zero, L::select(one < b1, one, b1));  // std::clamp
    b2 = L::select(b2 < zero, zero, L::select(one < b2, one, b2));
    const F s = b1 + b2;
    const auto over = s > one;
    if (W == 1 || any<W>(over)) b1 = L::select(over, b1 / s, b1), b2 = L::select(over, b2 / s, b2);
    const F nf = L::to_float(n);
    const F x = b1 * nf, y = b2 * nf;  // x + y <= n
    const I n1 = n - I(1);
    LatticeCellLanes<W> c;
    c.i = min(to_int(x), n1);
    c.j = min(to_int(y), n1 - c.i);
    const F ex = x - L::to_float(c.i), ey = y - L::to_float(c.j);
    F fx = L::select(ex < zero, zero, ex), fy = L::select(ey < zero, zero, ey);
    const F sum = fx + fy;
    const auto past = sum > one;
    c.upper = past & (c.i + c.j + I(2) <= n);
    const auto rescale = past & !c.upper;
    if (W == 1 || any<W>(rescale)) {
        const F inv = one / sum;
        fx = L::select(rescale, fx * inv, fx), fy = L::select(rescale, fy * inv, fy);
    }
    c.w0 = L::select(c.upper, fx + fy - one, one - fx - fy);
    c.w1 = L::select(c.upper, one - fx, fx);
    c.w2 = L::select(c.upper, one - fy, fy);
    return c;
}

struct LatticeCell {
    std::int32_t i, j;
    bool upper;
    float w0, w1, w2;
};
[[gnu::always_inline]] inline LatticeCell lattice_cell(std::int32_t n, float b1, float b2) {
    const LatticeCellLanes<1> c = lattice_cell_lanes<1>(n, b1, b2);
    return {c.i.v, c.j.v, c.upper.v, c.w0.v, c.w1.v, c.w2.v};
}

}  // namespace gigascroll
