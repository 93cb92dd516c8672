// The photon-mapping renderer: direct light by sampling the emitters with shadow rays,
// indirect light from the photon map at the first diffuse hit (VR-photon-mapping's pass 2).
//
// Pipelines (VR-photon-mapping Table 3 on a CPU):
//  - Fused: each pixel traces its ray, shades and gathers in one loop.
//  - TwoPass: all primary hits (with their direct light) first, then the gathers over the hit
//    points ordered by grid cell, so neighbouring gathers read the same photons.
// Cooperative gather (VR-photon-mapping Algorithm 1 on a CPU, TwoPass + hash grid + radius gather): a
// block of hit points in the same cell streams each photon of the 27 neighbouring cells once
// through all of them, instead of each hit point reading those photons itself.
//
// What a scene does not need is skipped: no photon pass when indirect light is off or no
// surface reflects; no gather (nor light sampling) for pixels that see nothing or a surface
// that does not reflect; no shadow ray toward a light whose front is turned away or that lies
// behind the surface.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "views/camera.h"
#include "photon/photon_map.h"
#include "photon/rng.h"
#include "photon/scene.h"

namespace gigascroll {

enum class Pipeline { Fused, TwoPass };
// "fused" / "two-pass"; InvalidArgument otherwise.
Pipeline parse_pipeline(const std::string& name);

struct RenderSettings {
    std::uint64_t photons = 1 << 18;
    GridKind grid = GridKind::Adaptive;  // the fastest gather; Hash is VR-photon-mapping's grid
    HashGrid::Mode hash_mode = HashGrid::Mode::Auto;
    GatherSettings gather;
    // Camera samples per pixel (box filter). One: jittered per pixel. More: the points of a
    // Roberts R2 lattice shifted by one random offset for the whole image (film_sample): each
    // pixel's samples spread over it evenly, and an edge that crosses a row of pixels at the
    // same height is covered by the same number of samples in each (no notched edges).
    int spp = 1;
    // Emitter samples per shading point. More than one: stratified (direct_irradiance).
    int light_samples = 1;
    std::uint64_t seed = 0;
    Pipeline pipeline = Pipeline::Fused;
    bool cooperative = false;
    bool direct = true;
    bool indirect = true;
    unsigned threads = 0;  // 0 = all cores
    void validate() const;
};

// Largest image a render accepts: 2^26 pixels (8192 x 8192; 768 MiB of float RGB, more with
// the per-pixel state of progressive and stereo renders). InvalidArgument with the memory the
// camera's resolution would need otherwise.
inline constexpr std::uint64_t kMaxRenderPixels = std::uint64_t(1) << 26;
void require_render_size(const Camera& camera, double bytes_per_pixel = 12);

struct RenderStats {
    double photon_seconds = 0;  // photon tracing
    double build_seconds = 0;   // hash grid or kd-tree construction
    double trace_seconds = 0;   // primary rays and direct light (two-pass: pass 1)
    double gather_seconds = 0;  // density estimation (two-pass: pass 2, including the sort)
    double total_seconds = 0;   // whole render of this view (photon pass included once)
    std::uint64_t photons_stored = 0;
    bool photon_pass_skipped = false;
    std::uint64_t gathers = 0, gathers_skipped = 0;
    std::uint64_t shadow_rays = 0, shadow_rays_skipped = 0;
    std::uint64_t reused_pixels = 0;  // stereo: right-eye pixels written by the left eye
};

// Per-thread counters, summed into RenderStats once per chunk.
struct ShadeCounters {
    std::uint64_t gathers = 0, gathers_skipped = 0, shadow_rays = 0, shadow_rays_skipped = 0;
};

// One emitter sample's share of the irradiance at `hit` (W / m^2 per channel, before the mean
// over samples): the sample's radiance x cos at the hit x cos at the light / (d^2 pdf_area), or
// zero when the light is behind the surface, faces away or a shadow ray finds it occluded.
Vec3f emitter_sample_irradiance(const Scene& scene, const Hit& hit, const LightSample& ls,
                                ShadeCounters& c);

// The same sample before its shadow ray: the share it adds when the ray finds the light, and
// that ray (origin, direction to the sample point, tfar as a fraction of the direction).
struct EmitterShadowRay {
    Vec3f contribution, origin, direction;
    float tfar;
};
// False (counted as a skipped shadow ray) when the light is behind the surface or faces away.
bool emitter_sample_unshadowed(const Scene& scene, const Hit& hit, const LightSample& ls, ShadeCounters& c,
                               EmitterShadowRay& ray);

class Renderer {
public:
    // Runs the photon pass (unless skipped) and builds the photon map.
    Renderer(const Scene& scene, const RenderSettings& settings);

    // Renders one view: linear RGB radiance, row-major (height, width, 3).
    std::vector<float> render(const Camera& camera, RenderStats& stats) const;

    // Emitted + direct + photon-map radiance leaving hit toward where its normal faces. Depends
    // on the hit point alone (Lambertian, samples seeded by position), not on the eye.
    Vec3f surface_radiance(const Hit& hit, KnnHeap& heap, ShadeCounters& c) const;
    // Flux density of the photon map at a hit point: the sphere gather of gather.h, or the
    // surface disc's when settings.gather.disc.
    Vec3f indirect_density(Vec3f p, Vec3f n, KnnHeap& heap) const;
    // Emission and direct light only; *needs_gather says whether the photon map applies.
    // `pass` selects the progressive pass's light samples (0 for one-shot renders).
    Vec3f emitted_and_direct(const Hit& hit, ShadeCounters& c, bool* needs_gather,
                             std::uint32_t pass = 0) const;
    // Direct irradiance at a hit point (W / m^2 per channel) from `samples` emitter samples
    // with shadow rays, seeded by position; the part of emitted_and_direct() before the albedo.
    // stratified (the renders' own shading): more than one sample is stratified over the
    // emitters and their area; false: independent samples (the gallery's lighting "full").
    Vec3f direct_irradiance(const Hit& hit, int samples, ShadeCounters& c,
                            std::uint32_t pass = 0, bool stratified = false) const;

    const RenderStats& photon_stats() const { return photon_stats_; }  // photon pass only
    const PhotonMap* photon_map() const { return map_.get(); }
    const Scene& scene() const { return scene_; }
    const RenderSettings& settings() const { return s_; }

    // Deterministic per-pixel sample stream of one view (stereo eye) and pass.
    Rng pixel_rng(int x, int y, int view, std::uint32_t pass = 0) const;
    // Film position of camera sample s of pixel (x, y) (see RenderSettings::spp); rng is the
    // pixel's stream (drawn from with one sample per pixel only).
    void film_sample(int x, int y, int s, Rng& rng, float& px, float& py) const;
    static void add(RenderStats& st, const ShadeCounters& c);

private:
    void render_fused(const Camera& cam, std::vector<float>& img, RenderStats& st) const;
    void render_two_pass(const Camera& cam, std::vector<float>& img, RenderStats& st) const;

    const Scene& scene_;
    RenderSettings s_;
    std::unique_ptr<PhotonMap> map_;
    RenderStats photon_stats_;
    double film_shift_[2] = {0.5, 0.5};  // the image's R2 lattice offset (film_sample)
};

}  // namespace gigascroll
