// The irradiance a planar Lambertian emitter of unit radiance gives a surface point with
// nothing in between: Lambert's polygon formula (the point-to-polygon form factor times pi),
//     E = 1/2 sum_k gamma_k (n . unit(v_k x v_k+1)),   v_k = unit(q_k - x),
// gamma_k the angle between v_k and v_k+1, after the polygon is clipped to the point's
// upper hemisphere (dot(n, q - x) > 0; Sutherland-Hodgman). It is the exact value of what
// emitter sampling estimates without shadow rays (the integral of cos_x cos_l / d^2 over the
// part of the emitter above the horizon), so a bake can pair it with the same samples' shadow
// rays (Heitz, Hill and McGuire 2018, "Combining analytic direct illumination and stochastic
// shadows": the ratio estimator in Gallery::direct_stratified).
#pragma once
#include <cmath>

#include "common/vec3.h"

namespace gigascroll {

// For a triangle (a, b, c) emitting on the side its winding normal (b - a) x (c - a) faces
// (a point behind it gets nothing, as one-sided emitter sampling gives), seen from x with
// normal n (|n| = 1). Bit k of skip_edges leaves out the terms of edge k (from vertex k to
// k + 1, clipped or not): an edge two coplanar emitter triangles of one radiance share
// (a quad light's diagonal) adds opposite terms in each, so the pair's sum without them is
// the quad's value for fewer terms; the parts are then signed and only their sum is >= 0.
inline float unit_triangle_irradiance(Vec3f x, Vec3f n, Vec3f a, Vec3f b, Vec3f c, unsigned skip_edges = 0) {
    const Vec3f winding = cross(b - a, c - a);
    if (!(dot(winding, x - a) > 0)) return 0;  // behind the emitter (or in its plane)
    const Vec3f q[3] = {a - x, b - x, c - x};
    const float h[3] = {dot(n, q[0]), dot(n, q[1]), dot(n, q[2])};
    // Clipped to the hemisphere h > 0 (at most four vertices), each output vertex tagged with
    // the original edge its outgoing edge lies on (3: the horizon).
    Vec3f p[4];
    int edge[4];
    int m = 0;
    for (int k = 0; k < 3; ++k) {
        const int l = (k + 1) % 3;
        if (h[k] > 0) p[m] = q[k], edge[m++] = k;
        if ((h[k] > 0) != (h[l] > 0)) {
            const float t = h[k] / (h[k] - h[l]);
            p[m] = q[k] + (q[l] - q[k]) * t, edge[m++] = h[l] > 0 ? k : 3;
        }
    }
    if (m < 3) return 0;
    Vec3f v[4];
    for (int k = 0; k < m; ++k) {
        const float len = length(p[k]);
        if (!(len > 0)) return 0;  // x on a vertex of the emitter: no usable value
        v[k] = p[k] * (1.0f / len);
    }
    float sum = 0;
    for (int k = 0; k < m; ++k) {
        if (edge[k] < 3 && (skip_edges >> edge[k] & 1)) continue;
        const Vec3f cr = cross(v[k], v[(k + 1) % m]);
        const float s = length(cr);
        if (!(s > 0)) continue;  // a zero-length edge adds nothing
        // atan2 rather than acos: accurate for the small angles of a distant emitter.
        sum += std::atan2(s, dot(v[k], v[(k + 1) % m])) * (dot(n, cr) / s);
    }
    // Seen from its front, the winding runs so that the terms sum to minus twice E.
    return -0.5f * sum;
}

}  // namespace gigascroll
