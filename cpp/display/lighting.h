// The scene's light as the display pass asks it (display/display_pass.h): per hit, the
// albedo of a surface that is not a painting, the irradiance arriving there and the emitted
// radiance; one call per 16-ray packet, or a baked lattice the pass reads itself in lanes
// (display/baked_lattice.h).
#pragma once
#include <cstddef>

#include "common/vec3.h"
#include "display/baked_lattice.h"

namespace gigascroll {

// What a surface point contributes beyond the painting's texture: the albedo of a surface
// that is not a painting (ignored on paintings, whose albedo is the texture), the irradiance
// arriving there (W / m^2 per channel) and the emitted radiance.
struct SurfaceLight {
    Vec3f albedo{0.5f, 0.5f, 0.5f};
    Vec3f irradiance{kPiF, kPiF, kPiF};
    Vec3f emission{0.0f, 0.0f, 0.0f};
    static constexpr float kPiF = float(3.14159265358979323846);
};

// One hit as the display pass hands it to the lighting: Embree geometry and primitive, the
// hit's barycentrics (Embree's u, v: p = (1 - b1 - b2) v0 + b1 v1 + b2 v2), the point and
// the unit normal facing the viewer.
struct LightQuery {
    unsigned geom = 0, prim = 0;
    float b1 = 0, b2 = 0;
    Vec3f p, n;
};

// The scene's lighting as the display pass asks it, per hit: Embree geometry and primitive,
// the point and the unit normal facing the viewer. Must be safe to call from many threads.
class DisplayLighting {
public:
    virtual ~DisplayLighting() = default;
    virtual void light(unsigned geom, unsigned prim, Vec3f p, Vec3f n, SurfaceLight& out) const = 0;
    // A packet of hits in one call (the display pass asks once per 16 rays, so the virtual
    // call is not paid per pixel). The default calls light() for each.
    virtual void light_batch(const LightQuery* queries, std::size_t count, SurfaceLight* out) const;
    // Lighting that is a baked lattice returns it (valid while the lighting lives), and the
    // display pass reads it in lanes instead of calling light_batch; nullptr: light_batch.
    virtual const BakedLattice* baked_lattice() const { return nullptr; }
};

// Today's unlit views: radiance = albedo (irradiance pi), grey occluders.
class UnlitLighting final : public DisplayLighting {
public:
    explicit UnlitLighting(Vec3f occluder_albedo = {0.5f, 0.5f, 0.5f}) : albedo_(occluder_albedo) {}
    void light(unsigned, unsigned, Vec3f, Vec3f, SurfaceLight& out) const override {
        out = SurfaceLight{};
        out.albedo = albedo_;
    }
    void light_batch(const LightQuery*, std::size_t count, SurfaceLight* out) const override {
        for (std::size_t i = 0; i < count; ++i) light(0, 0, {}, {}, out[i]);
    }

private:
    Vec3f albedo_;
};

}  // namespace gigascroll
