// The display pass at full resolution, for one eye or both (issue 14): one primary ray per
// pixel through the scene's BVH, the painting's albedo sampled through the virtual texture at
// the pixel's level of detail (trilinear), times the irradiance the scene supplies (baked or
// constant), plus emission; room surfaces the same with their own albedo.
//
// Stereo reuse (seed 001 §3.3, applied to display): every left-eye hit that faces the right
// eye is projected into the right image (Camera::project, eqs. 3-5) and claims that pixel with
// an atomic compare-and-swap on (depth, left pixel); the nearest claim wins. Claimed pixels
// on a depth edge of the claimed buffer are released again (a far sample must not show through
// a near surface that no left sample happened to land on), and the right eye traces only the
// pixels left unclaimed. A claimed pixel keeps the left hit's point and its light (irradiance,
// albedo, emission: view-independent on Lambertian surfaces) and takes its texture sample at
// the right eye's level of detail for the pixel (along its centre ray, as a traced pixel's
// level) at the left point (the left eye's sample when the levels agree to within
// reuse_lod_tolerance), so the reused pixel is what the right eye computes for that point.
//
// One sweep per eye (issue 14 §5): per row, 16-ray packets are traced. With a baked lattice
// on a CPU with AVX-512, a packet wholly on one surface (nearly every packet) is deferred and
// eight at a time are, stage by stage: lit from the lattice in 16 lanes (one or two affine
// functions of a lattice cell where the packet allows, else gathered), shaded at once on a
// room surface; on a painting mapped to the packet's first pixel's uv in double and its lanes'
// offsets in float (a per-eye plane map of each painting), sampled trilinearly in 16 lanes
// from that origin (TrilinearLanes, under one VT read lock for the frame) and shaded. Other
// packets are lit through DisplayLighting::light_batch (with Embree's barycentrics) or the
// lattice's lanes, their painting pixels mapped in double and sampled in runs of one painting
// at the row's end. Per pixel the pass keeps only the hit (point, normal, ids), the level, and
// for a left eye that the right eye reuses, its light. With reuse, when the eyes' rows align
// (the headset's case), both eyes run in one wavefront of 16-row chunks: a right chunk starts
// once the left chunks beside it have made their claims, while those claims and left rows are
// still in cache.
//
// The pass keeps its buffers between frames (one DisplayPass per stream of frames). Calls on
// one pass from several threads run one at a time (a render waits for the one under way),
// and its accessors wait for a render under way: its buffers are the frame's.
#pragma once
#include <embree3/rtcore.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <mutex>
#include <vector>

#include "cache/virtual_texture.h"
#include "common/vec3.h"
#include "views/camera.h"
#include "views/exhibition.h"

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

struct DisplayOptions {
    // Painting texels are sRGB-encoded; true decodes the filtered value to a linear albedo.
    bool srgb_albedo = true;
    // A painting's albedo = this x its (decoded) texel (the Gallery's kPaintingReflectance).
    float painting_reflectance = 1.0f;
    // A claimed right pixel whose depth exceeds an 8-neighbour's claimed depth by more than
    // this fraction is traced instead (see the header comment).
    float edge_depth_ratio = 0.05f;
    // A reused right pixel keeps the left eye's texture sample when its level of detail
    // differs from the left eye's by at most this (0: always re-sample at the right eye's).
    float reuse_lod_tolerance = 1.0f / 1024.0f;
    // Added to every pixel's level of detail (negative: sharper).
    float lod_bias = 0.0f;
    // false: render() (one eye) does not keep the hit points for hit_points(0), 16 bytes
    // per pixel stored that nobody reads in a frame (render_stereo keeps them: the right
    // eye reuses them).
    bool keep_hit_points = true;
    // render_stereo with reuse, eyes whose rows align: both eyes' rows in one wavefront, each
    // right chunk once the left rows it reads are done (false: the whole left eye first; the
    // same frame, for tests and benchmarks).
    bool interleave_eyes = true;
    unsigned threads = 0;  // 0 = all cores
};

// Per-eye times and counts of the last render(). The stages interleave row by row, so
// rays, vt and shade are the pass's wall time split in the proportion the threads spent in
// each on every 8th row (their sum is the pass's wall time).
struct EyeStats {
    double rays_seconds = 0;     // primary rays (the right eye: only the unclaimed pixels)
    double reuse_seconds = 0;    // right eye: projection, claims and edge release
    double vt_seconds = 0;       // uv, level of detail and virtual-texture sampling
    double shade_seconds = 0;    // lighting and the final colour
    std::uint64_t pixels = 0, hits = 0, traced = 0, reused = 0, painting_pixels = 0;
    double total_seconds() const { return rays_seconds + reuse_seconds + vt_seconds + shade_seconds; }
};

class DisplayPass {
public:
    // One eye into rgb (height x width x 3 linear floats; 0 where no surface is hit).
    void render(const PaintingSceneView& scene, const DisplayLighting& lighting,
                const VirtualTexture& vt, const Camera& eye, const DisplayOptions& options,
                float* rgb);
    // Both eyes (same resolution); reuse = false traces the right eye in full (the baseline).
    void render_stereo(const PaintingSceneView& scene, const DisplayLighting& lighting,
                       const VirtualTexture& vt, const Camera& left, const Camera& right,
                       bool reuse, const DisplayOptions& options, float* left_rgb, float* right_rgb);

    // Copies of the last frame's (taken under the pass's lock).
    EyeStats left_stats() const;
    EyeStats right_stats() const;
    // After render_stereo with reuse: per right pixel, the left pixel whose hit it reuses
    // (-1: traced), and the hit points of either eye (x, y, z per pixel; NaN where no hit;
    // InvalidArgument after a render() with keep_hit_points false).
    std::vector<std::int32_t> reuse_sources() const;
    std::vector<float> hit_points(int eye) const;
    // Per pixel of either eye: the level of detail sampled (NaN off paintings).
    std::vector<float> lods(int eye) const;

private:
    // What a frame keeps per pixel: the hit (for hit_points and the right eye's reused
    // pixels), the level, and for the left eye what a reused right pixel needs (its light).
    struct GBuffer {
        std::uint32_t width = 0, height = 0;
        std::vector<unsigned> geom;        // RTC_INVALID_GEOMETRY_ID: no hit
        std::vector<Vec3f> p;
        std::vector<float> lod;            // NaN off paintings
        // Left eye only (keep_light): per painting pixel its light, radiance = linear albedo x
        // scale + add (a reused right pixel whose level differs samples its own texel under
        // the left light; one whose level agrees copies the left radiance).
        std::vector<Vec3f> scale, add;
        void resize(std::uint32_t w, std::uint32_t h, bool keep_light);
    };
    // The fused pass over one eye: per row, 16-ray packets traced, their hits lit in one
    // lighting call and mapped to painting coordinates while they are in cache, then the
    // row's painting pixels sampled in runs and shaded. With claim_into (the left eye of a
    // stereo pair with reuse), each packet's hits claim the right eye's pixels they project
    // to, and the painting pixels keep their light. While reusing_ (the right eye), each row's
    // claims are released on depth edges just before the row is rendered; claimed pixels are
    // not traced: they take the left hit and light, and their texel at this eye's level.
    // How render_eye runs its rows: body(rb, re) on chunks of chunk_rows rows. Without one, a
    // parallel_for over the eye's rows; render_stereo's pair with reuse runs both eyes' chunks
    // in one wavefront (see render_stereo).
    using RowsBody = std::function<void(std::size_t, std::size_t)>;
    using RunRows = std::function<void(std::size_t chunk_rows, const RowsBody& body)>;
    // st's stage seconds are left as thread time of the timed rows in stage_ticks
    // (common/timing.h); the wall time of the call is returned for the caller to split among
    // the stages (split_wall).
    double render_eye(const PaintingSceneView& scene, const DisplayLighting& lighting,
                      const VirtualTexture& vt, const Camera& eye, const DisplayOptions& o,
                      GBuffer& g, const Camera* claim_into, const float* left_rgb, float* rgb,
                      EyeStats& st, const RunRows* run = nullptr);

    // Held by render, render_stereo and the accessors: one frame at a time per pass.
    mutable std::mutex mutex_;
    GBuffer g_[2];
    EyeStats stats_[2];
    std::vector<std::uint64_t> claims_;
    bool claims_clear_ = false;  // every claim is kUnclaimed (left so by the last right eye)
    bool reusing_ = false;  // the right eye being rendered reuses the left eye's hits
    bool hits_kept_ = true;  // the last frame kept the hit points (geom, p) of both eyes
    std::uint64_t frame_ = 0;  // this frame's number among all passes' (the workers' scratch)
    Vec3d origin_{0, 0, 0};    // the last frame's PaintingSceneView::origin (hit_points are world)
    std::vector<std::int32_t> sources_;
};

// A caller's output image for one eye as the binding sees it (any array), checked by
// check_output_image to be height x width x 3 float32, C-contiguous and writable, so that
// frames of a stream can be rendered into the same memory (no fresh pages, no page faults).
struct OutputImage {
    void* data = nullptr;
    std::size_t ndim = 0;
    const std::int64_t* shape = nullptr;
    const std::int64_t* strides = nullptr;  // in elements (nullptr: C-contiguous)
    bool float32 = false;
    bool writable = true;
};
// The checked image's floats; what names the argument in the message (ValueError).
float* check_output_image(const OutputImage& image, const Camera& eye, const char* what);
// Two output images of a stereo pair must not share memory (the right eye reads the left's).
void check_disjoint_images(const float* a, const float* b, std::size_t floats);

// The baseline of the display's cost: the same primary rays (16-ray packets along rows, as
// the pass casts them) with nothing done at the hits. Returns the seconds taken; *hits gets
// the number of rays that hit.
double cast_primary_rays(RTCScene scene, const Camera& eye, unsigned threads = 0,
                         std::uint64_t* hits = nullptr);

}  // namespace gigascroll
