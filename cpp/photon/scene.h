// A scene of Lambertian triangle meshes, some of them emissive (area lights), held in an
// Embree 3 BVH. Each triangle has an albedo (reflection, two-sided) and an emitted radiance
// (one-sided: toward the side its winding normal points to). A surface may do both.
#pragma once
#include <embree3/rtcore.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "common/embree_device.h"
#include "common/vec3.h"

namespace gigascroll {

struct Hit {
    float t = 0;
    Vec3f p;                  // hit position
    Vec3f n;                  // geometric normal, turned toward the ray origin
    std::uint32_t tri = 0;   // global triangle index
    bool front = false;      // ray arrived on the side the winding normal points to
};

// A point sampled on the emitters, with the density it was sampled with (per unit area).
struct LightSample {
    Vec3f p, n, radiance;
    float pdf_area = 0;
    std::uint32_t tri = 0;
};

// An albedo that varies over some triangles (a painting's texture): the photon tracer asks
// it through Scene::albedo_at() at each bounce. Not owned by the scene.
class AlbedoTexture {
public:
    virtual ~AlbedoTexture() = default;
    // The albedo at point p of triangle tri, or `constant` (the triangle's own) where the
    // texture does not cover tri.
    virtual Vec3f albedo(std::uint32_t tri, Vec3f p, Vec3f constant) const = 0;
};

class Scene {
public:
    Scene();
    ~Scene();
    Scene(const Scene&) = delete;
    Scene& operator=(const Scene&) = delete;

    // vertices: nv x 3 floats; triangles: nt x 3 indices; albedo: 3 floats, or nt x 3 when
    // per_triangle. Rejects non-finite vertices and those beyond +-1e12 (kMaxCoordinate), out-of-range indices and albedo outside
    // [0, 1). Degenerate (zero-area) triangles are dropped: they can be neither hit nor
    // sampled. Returns the number of triangles kept.
    std::size_t add_mesh(const float* vertices, std::size_t nv, const std::int64_t* triangles,
                         std::size_t nt, const float* albedo, bool per_triangle, Vec3f emission);
    // Moves every vertex by `offset` before commit (float addition per coordinate; the
    // Gallery holds a room far from the world's origin around the room, see Gallery::origin).
    void translate(Vec3f offset);
    void commit();  // builds the BVH and the emitter distribution; no add_mesh afterwards
    bool committed() const { return committed_; }

    // Nearest hit along o + t d for t in (0, tfar); d need not be normalised.
    bool intersect(Vec3f o, Vec3f d, Hit& hit, float tfar = INFINITY) const;
    // A camera's primary ray: intersect() ignoring hits nearer than epsilon() (a near clip
    // plane), so a camera standing on a surface, an edge or a vertex sees past the surfaces it
    // stands on instead of hitting them at t ~ 1e-8 (which rendered black).
    bool intersect_camera(Vec3f o, Vec3f d, Hit& hit) const { return intersect_range(o, d, hit, eps_, INFINITY); }
    // intersect() for a caller's own ray (Python's Scene.intersect): InvalidArgument unless
    // the scene is committed, o is within +-1e12 and d is finite, non-zero and within +-1e12.
    bool intersect_checked(Vec3f o, Vec3f d, Hit& hit) const;
    // True when something blocks o + t d for t in (0, tfar).
    bool occluded(Vec3f o, Vec3f d, float tfar) const;
    // occluded() for count <= 16 rays at once (one Embree packet: rays from one point to
    // one light share most of their traversal): out[k] for ray k.
    void occluded16(int count, const Vec3f* o, const Vec3f* d, const float* tfar, bool* out) const;

    // Picks an emissive triangle in proportion to its power, then a uniform point on it.
    LightSample sample_emitter(float u_tri, float u1, float u2) const;

    std::size_t triangle_count() const { return normal_.size(); }
    std::size_t emitter_count() const { return emitters_.size(); }
    Vec3f albedo(std::uint32_t tri) const { return albedo_[tri]; }
    // The albedo at a point: the texture's where one is set (set_albedo_texture), else albedo().
    Vec3f albedo_at(std::uint32_t tri, Vec3f p) const {
        return texture_ ? texture_->albedo(tri, p, albedo_[tri]) : albedo_[tri];
    }
    // Not thread-safe against tracing; the texture must outlive its use (nullptr removes it).
    void set_albedo_texture(const AlbedoTexture* texture) { texture_ = texture; }
    // The Embree BVH, for passes that cast their own rays into the same scene (the feedback
    // pass of a Gallery), and the number of Embree geometries (one per non-empty add_mesh,
    // ids 0, 1, ... in call order).
    RTCScene handle() const { return scene_; }
    std::uint32_t geometry_count() const { return std::uint32_t(geom_offset_.size()); }
    // The global triangle index of Embree primitive prim of geometry geom (as intersect() sets
    // Hit::tri), for passes that cast their own rays.
    std::uint32_t triangle_of(unsigned geom, unsigned prim) const { return geom_offset_[geom] + prim; }
    Vec3f emission(std::uint32_t tri) const { return emission_[tri]; }
    // The per-triangle arrays (indexed as triangle_of numbers them) and each geometry's first
    // triangle, for passes that read them in SIMD lanes (the display pass's baked lighting).
    const Vec3f* albedos() const { return albedo_.data(); }
    const Vec3f* emissions() const { return emission_.data(); }
    const Vec3f* normals() const { return normal_.data(); }
    const std::uint32_t* geometry_first_triangles() const { return geom_offset_.data(); }
    Vec3f normal(std::uint32_t tri) const { return normal_[tri]; }
    Vec3f emitted_power() const { return power_; }   // sum of pi * area * radiance
    float emitter_weight_total() const { return weight_total_; }
    bool reflects_anything() const { return reflects_; }
    Vec3f bounds_min() const { return lo_; }
    Vec3f bounds_max() const { return hi_; }
    float diagonal() const { return length(hi_ - lo_); }
    // Ray offset that keeps secondary rays off their own surface at any scene scale.
    float epsilon() const { return eps_; }
    // Seeds view-independent shading samples: quantises p within the scene bounds, so the
    // same point gives the same key from either eye and at any scene scale.
    std::uint64_t position_key(Vec3f p) const;

private:
    bool intersect_range(Vec3f o, Vec3f d, Hit& hit, float tnear, float tfar) const;
    void require_committed() const;
    EmbreeDevice device_;
    RTCScene scene_ = nullptr;
    bool committed_ = false;
    std::vector<std::uint32_t> geom_offset_;  // first global triangle of each geometry
    std::vector<std::size_t> geom_vertices_;  // vertices of each geometry (for translate)
    std::vector<Vec3f> albedo_, emission_, normal_;
    std::vector<Vec3f> tri_v0_, tri_e1_, tri_e2_;  // emitters only, indexed like emitters_
    std::vector<std::uint32_t> emitters_;
    std::vector<float> emitter_cdf_;
    // A guide table over emitter_cdf_ (the cutpoint method): entry b is the index
    // std::upper_bound finds for b / K, K = emitter_guide_.size() - 1 a power of two, so a
    // u in [b / K, (b + 1) / K) is searched between entries b and b + 1 only: the same
    // index as the whole binary search, in a step or two (the search's mispredicted
    // branches were 5% of a fine bake's 2.7 M emitter samples).
    std::vector<std::uint32_t> emitter_guide_;
    Vec3f power_{0, 0, 0};
    float weight_total_ = 0;
    bool reflects_ = false;
    Vec3f lo_{INFINITY, INFINITY, INFINITY}, hi_{-INFINITY, -INFINITY, -INFINITY};
    float eps_ = 1e-4f;
    const AlbedoTexture* texture_ = nullptr;
};

}  // namespace gigascroll
