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

SurfaceDisc make_surface_disc(const Scene& scene, Vec3f x, Vec3f n, float r) {
    // Nothing lies farther than the scene's diagonal: rays stay within it (and within the
    // range Embree accepts), whatever the radius.
    r = std::min(r, scene.diagonal());
    SurfaceDisc d = full_surface_disc(x, n, r);
    // Probes run half the tolerance above the surface: clear of it, below anything that
    // stands on it.
    const float lift = std::max(0.5f * d.thickness, 4.0f * scene.epsilon());
    const Vec3f o = x + n * lift;
    constexpr float kPi = float(M_PI);
    d.area = 0;
    for (int s = 0; s < SurfaceDisc::kSectors; ++s) {
        const float a = (float(s) + 0.5f) * (2.0f * kPi / SurfaceDisc::kSectors);
        const Vec3f dir = d.t * std::cos(a) + d.b * std::sin(a);
        Hit hit;
        float reach = r;
        if (scene.intersect(o, dir, hit, r)) reach = hit.t;  // a wall or partition
        // Where the surface ends (a border), the sector ends halfway from the last probe.
        float last = 0;
        for (int k = 1; k <= SurfaceDisc::kDepthProbes; ++k) {
            const float s_k = reach * float(k) / SurfaceDisc::kDepthProbes * 0.999f;
            Hit below;
            const bool surface = scene.intersect(o + dir * s_k, -n, below, lift + d.thickness) &&
                                 dot(below.n, n) > 0.5f;
            if (!surface) {
                reach = 0.5f * (last + s_k);
                break;
            }
            last = s_k;
        }
        d.reach2[s] = reach * reach;
        d.area += reach * reach * (kPi / SurfaceDisc::kSectors);  // sector of angle 2 pi / K
    }
    return d;
}

}  // namespace gigascroll
