// The Gallery's light as the full-resolution display pass asks it (display/display_pass.h):
// per hit, the room surface's albedo and emission and the irradiance there, baked or full,
// as Gallery::render_display computes them (baked: at Embree's barycentrics rather than the
// ones solved from the point, equal to float rounding). Holds the gallery's read lock while it
// lives, so light() and bake() cannot change what a frame reads.
#pragma once
#include <shared_mutex>

#include "gallery/gallery.h"
#include "display/display_pass.h"

namespace gigascroll {

class GalleryLighting final : public DisplayLighting {
public:
    // InvalidArgument when the lighting needs light() or bake() that has not been done.
    GalleryLighting(const Gallery& gallery, Lighting lighting);
    void light(unsigned geom, unsigned prim, Vec3f p, Vec3f n, SurfaceLight& out) const override;
    // Baked: the lattice at Embree's barycentrics, one call per packet (no point-to-barycentric
    // solve in double per pixel); unlit and full as light().
    void light_batch(const LightQuery* queries, std::size_t count, SurfaceLight* out) const override;
    // Baked: the scene's and the bake's arrays, for the display pass's lookup in lanes.
    const BakedLattice* baked_lattice() const override {
        return lighting_ == Lighting::Baked ? &lattice_ : nullptr;
    }
    // The display options that match the gallery's display (painting reflectance, sRGB).
    static DisplayOptions options(unsigned threads = 0);

private:
    const Gallery& gallery_;
    Lighting lighting_;
    std::shared_lock<std::shared_mutex> lock_;
    BakedLattice lattice_;
};

}  // namespace gigascroll
