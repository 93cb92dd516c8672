// The gallery: one room in which the paintings of a pack, streamed through the virtual
// texture, are lit by the room's light (VT-mobile-VR's paintings and streaming, VR-photon-mapping's light).
//
// One scene, one BVH. Room surfaces (Lambertian triangle meshes with albedo and emission) and
// painting rectangles are all triangles of one photon `Scene` (photon/scene.h), whose Embree
// BVH serves every ray: the feedback pass (views/feedback.h, through the PaintingSceneView
// this class hands it), the display pass, photon tracing and shadow rays. The shared scene
// lives in photon/ rather than views/ because it is the photon Scene that already holds the
// per-triangle albedo, emission and emitter distribution; views/ comes earlier in the include
// order, so the feedback pass takes a plain view (BVH handle, placements, geometry -> placement
// table) instead of a scene class, and the ExhibitionScene is one more provider of that view.
//
// Light on the paintings (issue 13 §2):
//  - light(): the photon pass (photon/photon_tracer.h, through Scene::albedo_at) over the
//    whole room into a PhotonMap (photon/photon_map.h) on the project's adaptive grid
//    (photon/adaptive_grid.h: VR-photon-mapping's hash grid with cells sized from the photon density,
//    queries walking only the cell rows their sphere or disc touches). A painting's albedo at a
//    photon's bounce comes from the virtual texture at the painting's finest pinned level, or
//    a coarser one for wide gathers (see PaintingAlbedo in gallery.cpp), so a red painting
//    bleeds red onto the floor. Photons
//    trapped between a painting and its wall are dropped before the map is built (see
//    drop_hidden_photons): through a 1 mm gap a gather on the painting would count them.
//    Direct light is the photon Renderer's emitter sampling (Renderer::direct_irradiance); the
//    bake's is by default the ratio estimator of BakeSettings::analytic_direct (the exact
//    unoccluded irradiance of the emitters times the visible fraction of its samples).
//  - Display radiance = albedo x E / pi + emission. A painting's albedo is the VT's trilinear
//    sample at the pixel's level of detail (kPaintingReflectance x the linearised sRGB texel);
//    E is direct light (emitter sampling, shadow rays) plus the photon gather (VR-photon-mapping eq. 1).
//  - bake(): E does not depend on the eye, so it is computed once per lighting on a lattice per
//    triangle and side (spacing in metres: a triangle whose longest edge is l gets
//    n = ceil(l / spacing) segments per edge, (n + 1)(n + 2) / 2 points) and interpolated
//    linearly at display time. lighting "full" computes E at every pixel: the oracle.
//
// Per-pixel hits for reprojection (the stereo walk's right-eye reuse): render_display fills,
// per pixel, the hit position (world, float, NaN where the ray escapes), the painting slot
// (-1 off paintings), the painting uv in [0, 1] and the level of detail lambda (NaN off
// paintings) and the irradiance E used there. A right-eye pixel that sees the same position can
// reuse the left eye's E (E is view-independent; the albedo is re-sampled at the right eye's
// lambda): radiance = albedo x E / pi + emission.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <shared_mutex>
#include <string>
#include <utility>
#include <vector>

#include "cache/virtual_texture.h"
#include "display/baked_lattice.h"
#include "display/srgb.h"
#include "pack/geometry.h"
#include "photon/renderer.h"
#include "photon/scene.h"
#include "photon/surface_disc.h"
#include "views/camera.h"
#include "views/exhibition.h"

namespace gigascroll {

// What a display pixel's irradiance comes from: none (the albedo itself: "unlit"), the baked
// lattice, or direct light and the photon gather at the pixel ("full").
enum class Lighting { Unlit, Baked, Full };
// "unlit" / "baked" / "full"; InvalidArgument otherwise.
Lighting parse_lighting(const std::string& name);

// A painting reflects this fraction of its linearised sRGB colour: varnished paint and gesso
// reflect at most about 90%, and an albedo below 1 keeps the light transport finite.
constexpr float kPaintingReflectance = 0.9f;

struct LightingSettings {
    std::uint64_t photons = 1u << 19;  // emitted photons
    float radius = 0;                  // gather radius in metres; 0 = auto (see light())
    int light_samples = 16;            // emitter samples per pixel in lighting "full"
    std::uint64_t seed = 0;
    unsigned threads = 0;              // 0 = all cores
    // Gather over the surface disc (photon/surface_disc.h: the query's plane only, clipped
    // where walls stand or the surface ends) instead of the sphere: no darkening at room edges
    // and painting borders, up to 24 rays per gather near other surfaces.
    bool disc = false;
    // false: direct light only; no photon pass, no photon map (the gather is zero).
    bool indirect = true;
};

struct BakeSettings {
    double spacing = 0;      // lattice spacing in metres; 0 = scene diagonal / 200
    int light_samples = 16;  // emitter samples per lattice point (stratified: see below)
    std::uint64_t max_points = 1ull << 25;  // a bound on memory (32 B per point)
    unsigned threads = 0;
    // Emitter samples stratified (the emitter choice in equal strata, the point on it from a
    // randomly shifted R2 lattice) instead of independent uniforms: unbiased (each sample is
    // uniform), and 3-5x less variance per point for the same count. false: the estimator of
    // lighting "full" (Renderer::direct_irradiance), sample for sample.
    bool stratified = true;
    // With stratified: the direct light as the ratio estimator of Heitz, Hill and McGuire
    // (2018): the exact unoccluded irradiance of the emitters (Lambert's polygon formula,
    // photon/polygon_irradiance.h) times the fraction of the samples' unoccluded contribution
    // that their shadow rays let through. Noise-free wherever a point sees all of the light or
    // none of it (most of a room), the same shadow rays as without it, and consistent (the
    // ratio's bias vanishes as the samples grow; it is confined to penumbrae). false: the
    // plain mean of the samples.
    bool analytic_direct = true;
    // With analytic_direct: the shadow rays of this many of the samples first (spread over
    // the strata); when they all reach the light, or none does, the point counts as fully lit
    // or fully shadowed and its other samples are not drawn (most points of a room: 16 samples
    // cost 4 rays there). The bias is confined to the edges of penumbrae whose probes agree by
    // chance. 0: every sample always.
    int shadow_probes = 4;
    // A side no light can reach is zero without its shadow rays and gather: every emitter
    // lies behind its plane (or faces away from the whole triangle), and no stored photon
    // whose normal the gather accepts lies within the gather radius of the triangle (tested
    // against the bounding boxes of the photons grouped by normal, so it is conservative).
    bool skip_unlit = true;
    // s = 2, 4 or 8: the photon gathers only at the points whose lattice coordinates are
    // multiples of s (a sub-lattice of s times the spacing; n is rounded up to a multiple of
    // s), linearly interpolated onto the others: 1 / s^2 of the gathers. The gather already
    // blurs indirect light over its radius, so this loses little while s x spacing stays
    // below the radius. 1: a gather at every point. The default, 2, is the quality knob's
    // `final` (python/gigascroll/gallery/quality.py), as are final_gather's and
    // sparse_final_gather's.
    int gather_stride = 2;
    // Lattice points on a triangle's edges and corners are computed a sixteenth of the
    // lattice spacing inside it (toward its centroid) rather than on the edge itself. The
    // room's edges are where surfaces meet: a point on the floor's edge also lies on the
    // wall's plane, so its shadow rays graze the wall (and are occluded by it or not, by
    // float rounding) and the surface disc's clipping rays start inside the wall. The lattice
    // interpolates those values over a whole cell next to every corner of the room. false: on
    // the edge (the value at the lattice point itself, as lighting "full" computes it there).
    bool inset_edges = true;
    // With light(disc = true): the bake's discs clipped coarsely (8 sectors, one probe and two
    // bisection steps: at most 32 rays instead of 128, SurfaceDisc::Detail::Coarse). The clipping
    // rays are most of a disc bake's time; in the hall this halves it for 5-15% more error.
    bool coarse_disc = false;
    // Lattice points that lie covered (under a painting lying on a table, on the wall behind a
    // hanging one, inside a plinth standing on the floor: every one of nine short probe rays,
    // along the normal and at 60 degrees around it, meets a surface within half the lattice
    // spacing) are not computed but filled from their uncovered neighbours on the triangle's
    // lattice, ring by ring, as lightmap bakers fill their invalid texels. Interpolation
    // across a covered region's border then no longer blends the dark point under the
    // painting into the lit table beside it (the band of one lattice cell that showed
    // stair-stepped beside the hall's paintings); nobody sees the covered point itself.
    bool fill_covered = true;
    // The photon gather's part of each lattice point (the indirect light; the direct light is
    // left as computed, so shadow edges stay sharp) smoothed over the triangle's own lattice by
    // a local linear fit (Gaussian weights of this many gather radii; covered points left
    // out): the photon map's density noise, which the bake froze into cloud-like patches at
    // the gather radius's scale, averaged over several gathers' worth of photons. A linear
    // fit rather than a mean, so that a gradient stays unbiased where the kernel is cut off
    // at the triangle's edge (no seam along a quad's diagonal). 0 (the default): off. Measured
    // in the scroll room (bench mottle, 2^19 photons): 1.5 radii take the painting's mottle
    // from 1.78% to 1.48% but raise the walls' and floor's (1.95% to 2.17%, 1.87% to 2.64%):
    // the fit spreads the sphere gather's darkening where a wall meets the floor.
    float indirect_filter = 0.0f;
    // Rays per lattice point of a final gather (Jensen): the indirect light as the mean of
    // albedo x E over that many cosine-distributed rays' hits, E there the lattice of a first
    // pass (direct light plus the photon map's density estimate): the photon noise at each
    // hit averages out over the hemisphere. The rays form a jittered grid when their count is
    // a square. 0: the density estimate at the point itself.
    int final_gather = 36;
    // With gather_stride s > 1: the final gather too only on the sub-lattice of every s-th
    // point (1 / s^2 of them; covered ones filled from their neighbours), interpolated between
    // (the indirect light it finds is smooth). The defaults, 36 rays a point on every other
    // point each way, take the mottle on walls and floors below 1% and on paintings below
    // 0.5% (bench mottle) for about 1.5x the light + bake time of no final gather.
    bool sparse_final_gather = true;
    // With final_gather: first-pass lattice points brighter (albedo x E) than this many times
    // the lattice's mean leave the gather and light each point as small area lights with a
    // shadow ray each, at most hot_samples of them per point (hot_lattice.h). 0: off.
    float hot_spots = 8.0f;
    int hot_samples = 16;
};

struct LightingStats {
    double photon_seconds = 0, build_seconds = 0, bake_seconds = 0;
    std::uint64_t photons_stored = 0, bake_points = 0;
    std::uint64_t bake_sides_skipped = 0;  // triangle sides skip_unlit set to zero
    std::uint64_t bake_points_covered = 0;  // lattice point sides fill_covered filled
    std::uint64_t bake_hot_points = 0;  // first-pass point sides hot_spots made lights
    float radius = 0;
    double spacing = 0;
    std::vector<std::uint32_t> albedo_levels;  // per painting slot: the level photons read
};

// Optional per-pixel outputs of render_display, each nullptr or width x height entries of
// the given size, row-major.
struct DisplayHits {
    float* position = nullptr;     // 3 per pixel
    std::int32_t* slot = nullptr;  // 1 per pixel
    double* uv = nullptr;          // 2 per pixel
    float* lod = nullptr;          // 1 per pixel
    float* irradiance = nullptr;   // 3 per pixel: E (W / m^2; pi in "unlit"), 0 where nothing is hit
};

struct BakeJob;     // bake_job.h: one bake's lattice layout and arrays
struct HotLattice;  // hot_lattice.h

class Gallery {
public:
    Gallery() = default;
    Gallery(const Gallery&) = delete;
    Gallery& operator=(const Gallery&) = delete;

    // A room surface: vertices nv x 3, triangles nt x 3; albedo in [0, 1), emission >= 0.
    // Returns the triangles kept (degenerate ones are dropped).
    std::size_t add_surface(const float* vertices, std::size_t nv, const std::int64_t* triangles,
                            std::size_t nt, Vec3f albedo, Vec3f emission);
    // A painting rectangle (see PaintingPlacement): `painting` is its id in the pack, `tiles`
    // its pyramid. u_axis, v_axis orthonormal; the painting faces u x v. Returns the slot.
    std::size_t add_painting(std::uint32_t painting, const PaintingGeometry& tiles, Vec3d origin,
                             Vec3d u_axis, Vec3d v_axis, double width_m, double height_m);
    // Builds the BVH. A room far from the world's origin is held around itself (origin()).
    void commit();
    bool committed() const { return scene_.committed(); }

    // The world position of the coordinates the room is held in: zero unless the room lies
    // far from the world's origin (see commit()). Cameras given to the gallery and positions
    // it returns (render_display's hits, bounds, intersect) are in world coordinates; scene(),
    // hits and paintings() inside are relative to origin().
    Vec3d origin() const { return origin_; }
    // The room's bounding box in world coordinates.
    std::pair<Vec3d, Vec3d> bounds() const;
    // The nearest hit along o + t d (world o; hit.p in world coordinates).
    bool intersect(Vec3d o, Vec3f d, Hit& hit) const;
    const Scene& scene() const { return scene_; }
    const std::vector<PaintingPlacement>& paintings() const { return placements_; }
    // The scene as the feedback pass takes it (views/feedback.h render_view).
    PaintingSceneView feedback_view() const;
    // Painting slot of a global triangle, -1 for room surfaces.
    int slot_of(std::uint32_t tri) const { return tri_slot_[tri]; }

    // The photon pass and photon map (replaces any previous lighting and bake). The VT must
    // hold the pack the paintings were added from. radius 0 picks
    // sqrt(100 A / (pi N)) for the room's area A and N photons (about 100 photons per disc),
    // clamped to [1e-4, 0.05] x the diagonal.
    void light(const VirtualTexture& vt, const LightingSettings& settings);
    bool lit() const {
        std::shared_lock lock(mutex_);
        return renderer_ != nullptr;
    }
    void bake(const BakeSettings& settings);
    // (lattice rows done, rows in all) of the bake running now or last; readable from any
    // thread while bake() runs (for a progress bar).
    std::pair<std::uint64_t, std::uint64_t> bake_progress() const {
        return {bake_done_.load(std::memory_order_relaxed), bake_total_.load(std::memory_order_relaxed)};
    }
    bool baked() const {
        std::shared_lock lock(mutex_);
        return !bake_offset_.empty();
    }
    // A copy, taken under the lock (light() and bake() may be rewriting it on another thread).
    LightingStats stats() const {
        std::shared_lock lock(mutex_);
        return stats_;
    }

    // One primary ray through each pixel centre: linear RGB radiance (height, width, 3).
    // Baked lighting without hits goes through the walk's packet display pass (DisplayPass
    // with GalleryLighting: the lattice and the plane map in vector lanes, 1.3-1.7x faster on
    // the bench's stills, equal to float rounding). `reference`, any hits output and the other
    // lightings take the per-pixel path (the plane map in double, one light lookup per pixel):
    // the oracle the packet pass is tested against.
    void render_display(const Camera& camera, const VirtualTexture& vt, Lighting lighting,
                        float* rgb, const DisplayHits& hits = {}, unsigned threads = 0,
                        bool reference = false) const;

    // Irradiance at a surface point on the side normal `n` faces (|n| = 1, toward the
    // viewer), as lighting "full" / "baked" compute it. For tests and reprojection.
    Vec3f irradiance_full(const Hit& hit) const;
    Vec3f irradiance_baked(const Hit& hit) const;
    // The baked lattice at barycentrics (b1, b2) of triangle tri (p = v0 + b1 e1 + b2 e2,
    // Embree's hit u, v), on the front or back side: irradiance_baked without recomputing the
    // barycentrics from the point. The caller holds read_lock() and the gallery is baked.
    Vec3f irradiance_baked_at(std::uint32_t tri, bool front, float b1, float b2) const;
    // The same for count points at once (the display pass's packets): out[i] for
    // (tri[i], front[i], b1[i], b2[i]).
    void irradiance_baked_batch(const std::uint32_t* tri, const bool* front, const float* b1,
                                const float* b2, std::size_t count, Vec3f* out) const;
    // Held by a display pass that calls the irradiance functions itself (gallery/display_lighting.h):
    // light() and bake() wait for it.
    std::shared_lock<std::shared_mutex> read_lock() const { return std::shared_lock(mutex_); }
    // The bake's lattices (bake_n_ and the rest below) for a display pass that interpolates
    // them itself in SIMD lanes; valid while read_lock() is held and the gallery is baked.
    struct BakeArrays {
        const std::uint32_t* segments;  // per triangle
        const std::uint64_t* offset;    // per triangle: its first lattice point
        const Vec3f *front, *back;      // per lattice point
        std::uint64_t points;
    };
    BakeArrays bake_arrays() const {
        return {bake_n_.data(), bake_offset_.data(), bake_front_.data(), bake_back_.data(), bake_front_.size()};
    }
    // Every kept triangle's frame p = v0 + b1 e1 + b2 e2 (its bake lattice's point (i, j) lies
    // at b1 = i / n, b2 = j / n): for exporting the bake as a mesh. Fixed once committed.
    struct TriangleFrames {
        const Vec3f *v0, *e1, *e2;
        std::size_t count;
    };
    TriangleFrames triangle_frames() const {
        return {tri_v0_.data(), tri_e1_.data(), tri_e2_.data(), tri_v0_.size()};
    }

private:
    // render_display's per-pixel path, the display pass's oracle (display_reference.cpp).
    struct DisplayOracle;
    void require_lit() const;
    void check_texture(const VirtualTexture& vt) const;
    Vec3f barycentric(std::uint32_t tri, Vec3f p) const;  // (b1, b2, 0) on tri's lattice
    // The photon map's flux density (the surface disc clipped at `detail` with light(disc)).
    Vec3f indirect(Vec3f p, Vec3f n, KnnHeap& heap,
                   SurfaceDisc::Detail detail = SurfaceDisc::Detail::Fine) const;
    // Direct irradiance from `samples` stratified emitter samples (BakeSettings::stratified).
    // analytic_probes >= 0: BakeSettings::analytic_direct with that many shadow_probes.
    Vec3f direct_stratified(const Hit& hit, int samples, ShadeCounters& c, int analytic_probes = -1) const;
    // BakeSettings::final_gather at p (normal n): `rays` cosine rays looking up the first
    // pass's lattices (front, back; segments, offset per triangle).
    Vec3f final_gather(Vec3f p, Vec3f n, int rays, const std::vector<Vec3f>& front, const std::vector<Vec3f>& back,
                       const std::vector<std::uint32_t>& segments, const std::vector<std::uint64_t>& offset) const;
    // bake()'s steps in the order they run (gallery.cpp says what each does).
    void bake_lattice_layout(BakeJob& job) const;
    void bake_allocate(BakeJob& job);
    Vec3f bake_point(const BakeJob& job, std::uint32_t t, std::uint32_t i, std::uint32_t j) const;
    void bake_first_pass(BakeJob& job);
    void bake_interpolate(BakeJob& job, const std::vector<Vec3f>& sub_f, const std::vector<Vec3f>& sub_b,
                          std::vector<Vec3f>& out_f, std::vector<Vec3f>& out_b, bool add);
    void bake_add_indirect(BakeJob& job);
    void bake_fill_covered(BakeJob& job);
    void bake_fill(BakeJob& job, std::vector<Vec3f>& f, std::vector<Vec3f>& b, std::vector<std::uint8_t>& mf,
                   std::vector<std::uint8_t>& mb, const std::vector<std::uint64_t>& off,
                   const std::vector<std::uint32_t>& n, std::uint32_t divisor);
    void bake_final_gather_pass(BakeJob& job);
    void bake_final_gather_rows(BakeJob& job, const HotLattice& hot);
    void bake_commit(BakeJob& job);
    // The emitters' irradiance at p (normal n) with nothing in between (BakeSettings::analytic_direct).
    Vec3f unoccluded_irradiance(Vec3f p, Vec3f n) const;
    // Whether light can reach side n (= +-normal) of triangle t (BakeSettings::skip_unlit).
    bool side_reachable(std::uint32_t t, Vec3f n) const;
    void group_photons(const std::vector<Photon>& photons);  // fills photon_groups_

    Scene scene_;
    Vec3d origin_{0, 0, 0};
    std::vector<PaintingPlacement> placements_;
    std::vector<int> geom_placement_;   // Embree geometry id -> painting slot or -1
    std::vector<int> tri_slot_;         // global triangle -> painting slot or -1
    std::vector<std::uint32_t> geom_first_tri_;  // Embree geometry id -> its first triangle
    std::vector<Vec3f> tri_v0_, tri_e1_, tri_e2_;  // every kept triangle
    // Per triangle, barycentric()'s Gram terms dot(e1, e1), dot(e1, e2), dot(e2, e2) and their
    // determinant, computed once at commit() (the same float and double operations as per
    // call: the same bits) rather than at every baked display pixel.
    struct BarycentricTerms {
        double d00, d01, d11, denom;
    };
    std::vector<BarycentricTerms> tri_terms_;
    std::vector<std::uint32_t> emitter_tris_;  // the triangles that emit, in order (side_reachable)
    std::vector<std::uint8_t> emitter_shared_edges_;  // per emitter triangle: edges shared in a quad
    LightingSettings lighting_;
    std::unique_ptr<AlbedoTexture> albedo_;
    std::unique_ptr<Renderer> renderer_;  // direct light (emitter sampling, shadow rays)
    std::unique_ptr<PhotonMap> map_;      // indirect light: the adaptive grid of photon/
    std::vector<Photon> photon_scratch_;  // light()'s photon list, its capacity reused when relit
    GatherSettings gather_;
    // The stored photons grouped by (quantised) normal: a normal and the box of the group's
    // positions, for side_reachable; empty with photon_groups_overflow_ when there are too
    // many groups to be useful (then every side counts as reachable).
    struct PhotonGroup {
        Vec3f n, lo, hi;
    };
    std::vector<PhotonGroup> photon_groups_;
    bool photon_groups_overflow_ = false;
    // Bake: triangle t's lattice has bake_n_[t] segments and its points start at
    // bake_offset_[t]; front and back side irradiance per point.
    std::vector<std::uint32_t> bake_n_;
    std::vector<std::uint64_t> bake_offset_;
    std::vector<Vec3f> bake_front_, bake_back_;
    LightingStats stats_;
    std::atomic<std::uint64_t> bake_done_{0}, bake_total_{0};
    // light() and bake() replace what render_display reads: they exclude it.
    mutable std::shared_mutex mutex_;
};

}  // namespace gigascroll
