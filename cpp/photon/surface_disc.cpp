#include "photon/surface_disc.h"

#include <algorithm>
#include <cmath>

namespace gigascroll {

namespace {
// Thickness tolerance as a share of the radius: covers the sagitta of curved tessellated
// surfaces (r^2 / 2R: 0.025 r on the furnace sphere at r = 0.05) yet rejects a surface 2 cm
// behind at the default radius (0.1 r = 6 mm in the test rooms).
constexpr float kThickness = 0.1f;
}  // namespace

SurfaceDisc full_surface_disc(Vec3f x, Vec3f n, float r) {
    SurfaceDisc d;
    d.x = x;
    d.n = n;
    d.r = r;
    d.thickness = kThickness * r;
    basis(n, d.t, d.b);
    for (float& r2 : d.reach2) r2 = r * r;
    d.area = float(M_PI) * r * r;
    return d;
}

SurfaceDisc make_surface_disc(const Scene& scene, Vec3f x, Vec3f n, float r, SurfaceDisc::Detail detail) {
    // Nothing lies farther than the scene's diagonal: rays stay within it (and within the
    // range Embree accepts), whatever the radius.
    r = std::min(r, scene.diagonal());
    SurfaceDisc d = full_surface_disc(x, n, r);
    // Probes run half the tolerance above the surface: clear of it, below anything that
    // stands on it.
    const float lift = std::max(0.5f * d.thickness, 4.0f * scene.epsilon());
    const Vec3f o = x + n * lift;
    constexpr float kPi = float(M_PI);
    // A point of the sector's ray belongs to the disc when the query's own surface lies just
    // below it and nothing overhangs it within r: a painting hung 2 cm in front of a wall
    // covers the wall behind its rim, which the in-plane ray (3 mm up) passes under but which
    // its shadow keeps dark, as a lamp's shade keeps the ceiling above it.
    // One ray down from r above q tells both: the first thing it meets above q's height covers
    // q; else q is on the surface if the ray meets it within the tolerance below q.
    enum class Probe { On, Off, Covered };
    auto probe = [&](Vec3f q) {
        Hit hit;
        if (!scene.intersect(q + n * r, -n, hit, r + lift + d.thickness)) return Probe::Off;
        if (hit.t < r) return Probe::Covered;
        return dot(hit.n, n) > 0.5f ? Probe::On : Probe::Off;
    };
    const bool coarse = detail == SurfaceDisc::Detail::Coarse;
    const int sectors = coarse ? SurfaceDisc::kSectors / 2 : SurfaceDisc::kSectors;
    const int depth_probes = coarse ? 1 : SurfaceDisc::kDepthProbes;
    const int refinements = coarse ? 2 : SurfaceDisc::kRefinements;
    float covered = r;  // nearest covered point over the sectors
    d.area = 0;
    for (int s = 0; s < sectors; ++s) {
        const float a = (float(s) + 0.5f) * (2.0f * kPi / float(sectors));
        const Vec3f dir = d.t * std::cos(a) + d.b * std::sin(a);
        Hit hit;
        float reach = r;
        bool clipped = false;
        if (scene.intersect(o, dir, hit, r)) {  // a wall or partition
            reach = hit.t;
            clipped = true;
        }
        // Probes at 1/2 and 1 of the reach; where one fails (the surface ends or is covered),
        // bisection between the last point on the surface and the first off it, and the
        // sector ends at the last point on it.
        float good = 0, bad = -1;
        Probe bad_kind = Probe::On;
        for (int k = 1; k <= depth_probes; ++k) {
            const float s_k = reach * float(k) / float(depth_probes) * 0.999f;
            const Probe p = probe(o + dir * s_k);
            if (p != Probe::On) {
                bad = s_k;
                bad_kind = p;
                break;
            }
            good = s_k;
        }
        if (bad >= 0) {
            for (int i = 0; i < refinements; ++i) {
                const float mid = 0.5f * (good + bad);
                const Probe p = probe(o + dir * mid);
                if (p == Probe::On) {
                    good = mid;
                } else {
                    bad = mid;
                    bad_kind = p;
                }
            }
            if (bad_kind == Probe::Covered) covered = std::min(covered, bad);
            reach = good;
            clipped = true;
        }
        // A boundary crossing the sector obliquely comes nearer than along its middle ray, by
        // up to cos(pi / K) for a straight one: the sector keeps the near side of it.
        if (clipped) reach *= std::cos(kPi / float(sectors));
        if (coarse) {  // an octant: both of its sixteenths
            d.reach2[2 * s] = d.reach2[2 * s + 1] = reach * reach;
        } else {
            d.reach2[s] = reach * reach;
        }
    }
    // Next to an occluder the irradiance changes within the distance to it (the painting's
    // rim darkens the wall just outside it): the disc shrinks to twice that distance there, so
    // that it spans about as far on the open side as on the covered one, but not below a
    // quarter of r (a sixteenth of its photons).
    if (covered < r) {
        const float cap = std::max(2.0f * covered, 0.125f * r);
        for (float& r2 : d.reach2) r2 = std::min(r2, cap * cap);
    }
    d.area = 0;
    for (float r2 : d.reach2) d.area += r2 * (kPi / SurfaceDisc::kSectors);  // sectors of angle 2 pi / K
    return d;
}

}  // namespace gigascroll
