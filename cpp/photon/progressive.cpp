#include "photon/progressive.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "common/timing.h"
#include "common/error.h"
#include "common/parallel.h"
#include "photon/adaptive_grid.h"
#include "photon/hash_grid.h"
#include "photon/photon_tracer.h"
#include "photon/rng.h"
#include "photon/surface_disc.h"

namespace gigascroll {

namespace {

// A pixel's running SPPM statistics, and this pass's visible point.
struct PixelState {
    Vec3f direct{0, 0, 0};  // sum over passes of emitted + direct light
    Vec3f tau{0, 0, 0};     // accumulated reflected flux (f_r included)
    double n = 0;           // accumulated photon count
    float r = 0;            // current radius
    Vec3f p, normal, f;     // visible point: position, normal, f_r = albedo / pi
    bool has_point = false;
};
}  // namespace

void ProgressiveSettings::validate() const {
    require(passes >= 1 && std::uint32_t(passes) <= kMaxPasses, "render: passes must be in [1, 2^24]");
    require(std::isfinite(time_budget) && time_budget >= 0, "render: time_budget must be finite and >= 0");
    require(std::isfinite(alpha) && alpha > 0 && alpha < 1, "render: alpha must be in (0, 1)");
    require(coarse_passes >= 0, "render: coarse_passes must be >= 0");
}

namespace {
void check_progressive(const RenderSettings& settings, const ProgressiveSettings& prog, const Camera& cam) {
    settings.validate();
    prog.validate();
    require(settings.spp == 1, "render: progressive rendering takes one camera sample per pixel and pass "
                               "(raise passes instead of spp)");
    require(!settings.gather.knn && settings.gather.kernel == Kernel::Box && settings.grid != GridKind::KdTree &&
                settings.pipeline == Pipeline::Fused && !settings.cooperative,
            "render: progressive rendering uses a grid's box radius gather (no knn, cone, kdtree, "
            "two-pass or cooperative options)");
    require_render_size(cam, 12 + sizeof(PixelState));
}

// Progressive photon mapping's passes over one image: per pass the pixels' visible points
// (with their emitted and direct light), a photon map, and each point's gather shrinking its
// radius (SPPM); the image resolved from the running statistics.
class ProgressivePass {
public:
    ProgressivePass(const Scene& scene, const Camera& cam, const RenderSettings& settings,
                    const ProgressiveSettings& prog, ProgressiveStats& stats)
        : scene_(scene), cam_(cam), settings_(settings), prog_(prog), stats_(stats),
          R_(scene, shading(settings)),
          photons_needed_(settings.indirect && scene.emitter_count() > 0 && scene.reflects_anything()),
          w_(int(cam.width)), h_(int(cam.height)), npix_(std::size_t(w_) * std::size_t(h_)), px_(npix_),
          img_(npix_ * 3, 0.0f) {
        for (auto& s : px_) s.r = settings.gather.radius;
        stats_ = ProgressiveStats{};
        stats_.render.photon_pass_skipped = !photons_needed_;
    }

    // Pass k (from 0): visible points, then the photons and their gathers.
    void pass(int k) {
        auto t0 = Clock::now();
        parallel_for(std::size_t(h_), 4, [&](std::size_t yb, std::size_t ye) { visible_rows(k, yb, ye); },
                     settings_.threads);
        stats_.render.trace_seconds += seconds_since(t0);
        if (!photons_needed_) return;
        t0 = Clock::now();
        const std::vector<Photon> photons =
            trace_photons(scene_, settings_.photons, settings_.seed, settings_.threads, nullptr, std::uint32_t(k));
        stats_.render.photon_seconds += seconds_since(t0);
        stats_.render.photons_stored += photons.size();
        t0 = Clock::now();
        float r_max = 0;
        for (const PixelState& s : px_)
            if (s.has_point) r_max = std::max(r_max, s.r);
        // One gather pass over either grid; the adaptive grid culls its cells against each
        // pixel's own (shrinking) radius, VR-photon-mapping's grid visits the cells of r_max.
        if (r_max > 0 && !photons.empty()) {
            if (settings_.grid == GridKind::Adaptive) gather_pass(AdaptiveGrid(photons, r_max), k, t0);
            else gather_pass(HashGrid(photons, r_max, settings_.hash_mode), k, t0);
        }
    }

    // The image after k passes.
    const std::vector<float>& resolve(int k) {
        const float inv_k = 1.0f / float(k);
        parallel_for(npix_, 1024, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) {
                const PixelState& s = px_[i];
                Vec3f v = s.direct * inv_k;
                if (s.r > 0) v += s.tau * (inv_k / (float(M_PI) * s.r * s.r));
                img_[3 * i] = v.x; img_[3 * i + 1] = v.y; img_[3 * i + 2] = v.z;
            }
        }, settings_.threads);
        return img_;
    }

    // The mean radius of the pixels that gathered anything (the start radius if none).
    double mean_radius() const {
        double rsum = 0;
        std::size_t rn = 0;
        for (const PixelState& s : px_)
            if (s.n > 0) {
                rsum += s.r;
                ++rn;
            }
        return rn ? rsum / double(rn) : double(settings_.gather.radius);
    }
    std::vector<float> take_image() { return std::move(img_); }

private:
    // The shading helpers (emission, direct light) without a photon map of their own.
    static RenderSettings shading(RenderSettings s) {
        s.indirect = false;
        return s;
    }

    // Rows [yb, ye)'s visible points in pass k, with their emitted and direct light.
    void visible_rows(int k, std::size_t yb, std::size_t ye) {
        const auto pass = std::uint32_t(k);
        ShadeCounters c;
        for (std::size_t y = yb; y < ye; ++y)
            for (int x = 0; x < w_; ++x) {
                PixelState& s = px_[y * std::size_t(w_) + std::size_t(x)];
                Rng rng = R_.pixel_rng(x, int(y), 0, pass);
                const float fx = float(x) + rng.uniform(), fy = float(y) + rng.uniform();
                Hit hit;
                s.has_point = false;
                if (!scene_.intersect_camera(cam_.ray_origin(), cam_.ray_direction(fx, fy), hit)) continue;
                bool unused = false;
                s.direct += R_.emitted_and_direct(hit, c, &unused, pass);
                const Vec3f albedo = scene_.albedo(hit.tri);
                if (!photons_needed_ || !(max_component(albedo) > 0)) continue;
                Vec3f f = albedo * float(1.0 / M_PI);
                if (prog_.final_gather) {
                    // Cosine sampling: f_r cos / pdf = albedo. The bounce's emission is the
                    // first hit's direct light, already sampled; its direct light is added
                    // here and its photons are gathered below.
                    const Vec3f d = sample_cosine(hit.n, rng.uniform(), rng.uniform());
                    const Vec3f o = hit.p + hit.n * scene_.epsilon();
                    Hit next;
                    if (!scene_.intersect(o, d, next)) continue;
                    const Vec3f next_albedo = scene_.albedo(next.tri);
                    if (!(max_component(next_albedo) > 0)) continue;
                    f = albedo * next_albedo * float(1.0 / M_PI);
                    if (settings_.direct) s.direct += f * R_.direct_irradiance(next, settings_.light_samples, c, pass);
                    hit = next;
                }
                s.has_point = true;
                s.p = hit.p;
                s.normal = hit.n;
                s.f = f;
            }
        std::lock_guard lock(m_);
        Renderer::add(stats_.render, c);
    }

    // Every visible point's gather from the grid, its statistics updated (t0: the grid's
    // build started).
    template <typename Grid>
    void gather_pass(const Grid& grid, int k, Clock::time_point t0) {
        stats_.render.build_seconds += seconds_since(t0);
        t0 = Clock::now();
        const auto detail = k < prog_.coarse_passes ? SurfaceDisc::Detail::Coarse : SurfaceDisc::Detail::Fine;
        std::uint64_t gathers = 0;
        parallel_for(npix_, 256, [&](std::size_t b, std::size_t e) {
            std::uint64_t g = 0;
            for (std::size_t i = b; i < e; ++i)
                if (px_[i].has_point) g += gather(grid, px_[i], detail);
            std::lock_guard lock(m_);
            gathers += g;
        }, settings_.threads);
        stats_.render.gathers += gathers;
        stats_.render.gather_seconds += seconds_since(t0);
    }

    // One visible point's gather and its SPPM update; 1 (a gather made).
    template <typename Grid>
    std::uint64_t gather(const Grid& grid, PixelState& s, SurfaceDisc::Detail detail) const {
        float found = 0;
        Vec3f power;
        if (settings_.gather.disc) {
            // The clipped disc's flux, scaled to the full disc's area so the final
            // tau / (pi R^2) divides by the area actually gathered.
            const DiscEstimate d = gather_surface_disc(scene_, grid, s.p, s.normal, s.r, detail);
            const float full = float(M_PI) * s.r * s.r;
            if (!(d.area > 1e-3f * full)) return 1;
            power = d.power * (full / d.area);
            found = d.count;
        } else {
            power = grid.sum_box(s.p, s.normal, s.r * s.r, &found);
        }
        if (!(found > 0)) return 1;
        const double n_new = s.n + prog_.alpha * double(found);
        const double shrink2 = n_new / (s.n + double(found));  // (R' / R)^2
        s.tau = (s.tau + s.f * power) * float(shrink2);
        s.r *= float(std::sqrt(shrink2));
        s.n = n_new;
        return 1;
    }

    const Scene& scene_;
    const Camera& cam_;
    const RenderSettings& settings_;
    const ProgressiveSettings& prog_;
    ProgressiveStats& stats_;
    const Renderer R_;
    const bool photons_needed_;
    const int w_, h_;
    const std::size_t npix_;
    std::vector<PixelState> px_;
    std::vector<float> img_;
    std::mutex m_;
};
}  // namespace

std::vector<float> render_progressive(const Scene& scene, const Camera& cam, const RenderSettings& settings,
                                      const ProgressiveSettings& prog, ProgressiveStats& stats,
                                      const PassCallback& on_pass) {
    check_progressive(settings, prog, cam);
    const auto t_start = Clock::now();
    ProgressivePass pp(scene, cam, settings, prog, stats);
    int k = 0;
    while (k < prog.passes) {
        pp.pass(k);
        ++k;
        const double elapsed = seconds_since(t_start);
        if (on_pass) on_pass(k, pp.resolve(k), elapsed);
        if (prog.time_budget > 0 && elapsed >= prog.time_budget) break;
    }
    if (!on_pass) pp.resolve(k);
    stats.passes = k;
    stats.mean_radius = pp.mean_radius();
    stats.render.total_seconds = seconds_since(t_start);
    return pp.take_image();
}

}  // namespace gigascroll
