#include "gallery/display_lighting.h"

#include <algorithm>
#include <cmath>

#include "common/error.h"

namespace gigascroll {

GalleryLighting::GalleryLighting(const Gallery& gallery, Lighting lighting)
    : gallery_(gallery), lighting_(lighting), lock_(gallery.read_lock()) {
    require(gallery.committed(), "Gallery: commit() before rendering");
    require(lighting == Lighting::Unlit || gallery.lit(),
            "Gallery: call light() before rendering with lighting");
    require(lighting != Lighting::Baked || gallery.baked(),
            "Gallery: call bake() before lighting 'baked'");
    if (lighting == Lighting::Baked) {
        const Scene& scene = gallery.scene();
        const Gallery::BakeArrays bake = gallery.bake_arrays();
        lattice_.first_triangle = scene.geometry_first_triangles();
        lattice_.normal = scene.normals(), lattice_.albedo = scene.albedos();
        lattice_.emission = scene.emissions();
        lattice_.segments = bake.segments, lattice_.offset = bake.offset;
        lattice_.front = bake.front, lattice_.back = bake.back;
        lattice_.triangles = scene.triangle_count(), lattice_.points = bake.points;
    }
}

void GalleryLighting::light(unsigned geom, unsigned prim, Vec3f p, Vec3f n, SurfaceLight& out) const {
    const Scene& scene = gallery_.scene();
    Hit hit;
    hit.p = p;
    hit.tri = scene.triangle_of(geom, prim);
    // The scene's own normal turned toward the eye, as Scene::intersect sets it.
    const Vec3f winding = scene.normal(hit.tri);
    hit.front = dot(winding, n) > 0;  // n faces the eye
    hit.n = hit.front ? winding : -winding;
    switch (lighting_) {
        case Lighting::Unlit: out.irradiance = Vec3f(float(M_PI), float(M_PI), float(M_PI)); break;
        case Lighting::Baked: out.irradiance = gallery_.irradiance_baked(hit); break;
        case Lighting::Full: out.irradiance = gallery_.irradiance_full(hit); break;
    }
    out.albedo = scene.albedo(hit.tri);
    out.emission = hit.front ? scene.emission(hit.tri) : Vec3f(0, 0, 0);
}

void GalleryLighting::light_batch(const LightQuery* queries, std::size_t count,
                                  SurfaceLight* out) const {
    if (lighting_ != Lighting::Baked) {
        DisplayLighting::light_batch(queries, count, out);
        return;
    }
    const Scene& scene = gallery_.scene();
    std::uint32_t tri[16];
    bool front[16];
    float b1[16], b2[16];
    Vec3f E[16];
    for (std::size_t k0 = 0; k0 < count; k0 += 16) {
        const std::size_t n = std::min<std::size_t>(16, count - k0);
        for (std::size_t k = 0; k < n; ++k) {
            const LightQuery& q = queries[k0 + k];
            tri[k] = scene.triangle_of(q.geom, q.prim);
            front[k] = dot(scene.normal(tri[k]), q.n) > 0;  // q.n faces the eye
            b1[k] = q.b1, b2[k] = q.b2;
        }
        gallery_.irradiance_baked_batch(tri, front, b1, b2, n, E);
        // A packet's hits mostly share a triangle: its albedo and emission read once.
        std::uint32_t last = ~0u;
        Vec3f albedo, emission;
        for (std::size_t k = 0; k < n; ++k) {
            if (tri[k] != last) last = tri[k], albedo = scene.albedo(last), emission = scene.emission(last);
            SurfaceLight& o = out[k0 + k];
            o.irradiance = E[k];
            o.albedo = albedo;
            o.emission = front[k] ? emission : Vec3f(0, 0, 0);
        }
    }
}

DisplayOptions GalleryLighting::options(unsigned threads) {
    DisplayOptions o;
    o.srgb_albedo = true;
    o.painting_reflectance = kPaintingReflectance;
    o.keep_hit_points = false;  // the walk's one-eye displays read only the image
    o.threads = threads;
    return o;
}

}  // namespace gigascroll
