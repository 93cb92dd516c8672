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

std::vector<float> render_progressive(const Scene& scene, const Camera& cam, const RenderSettings& settings,
                                      const ProgressiveSettings& prog, ProgressiveStats& stats,
                                      const PassCallback& on_pass) {
    settings.validate();
    prog.validate();
    require(settings.spp == 1, "render: progressive rendering takes one camera sample per pixel and pass "
                               "(raise passes instead of spp)");
    require(!settings.gather.knn && settings.gather.kernel == Kernel::Box && settings.grid != GridKind::KdTree &&
                settings.pipeline == Pipeline::Fused && !settings.cooperative,
            "render: progressive rendering uses a grid's box radius gather (no knn, cone, kdtree, "
            "two-pass or cooperative options)");
    require_render_size(cam, 12 + sizeof(PixelState));
    const auto t_start = Clock::now();
    // The shading helpers (emission, direct light) without a photon map of their own.
    RenderSettings shading = settings;
    shading.indirect = false;
    const Renderer R(scene, shading);
    const bool photons_needed = settings.indirect && scene.emitter_count() > 0 && scene.reflects_anything();

    const int w = int(cam.width), h = int(cam.height);
    const std::size_t npix = std::size_t(w) * std::size_t(h);
    std::vector<PixelState> px(npix);
    for (auto& s : px) s.r = settings.gather.radius;
    std::vector<float> img(npix * 3, 0.0f);
    stats = ProgressiveStats{};
    stats.render.photon_pass_skipped = !photons_needed;
    std::mutex m;

    auto resolve = [&](int k) {  // the image after k passes
        const float inv_k = 1.0f / float(k);
        parallel_for(npix, 1024, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) {
                const PixelState& s = px[i];
                Vec3f v = s.direct * inv_k;
                if (s.r > 0) v += s.tau * (inv_k / (float(M_PI) * s.r * s.r));
                img[3 * i] = v.x; img[3 * i + 1] = v.y; img[3 * i + 2] = v.z;
            }
        }, settings.threads);
    };

    int k = 0;
    while (k < prog.passes) {
        const auto pass = std::uint32_t(k);
        // Visible points, with their emitted and direct light.
        auto t0 = Clock::now();
        parallel_for(std::size_t(h), 4, [&](std::size_t yb, std::size_t ye) {
            ShadeCounters c;
            for (std::size_t y = yb; y < ye; ++y)
                for (int x = 0; x < w; ++x) {
                    PixelState& s = px[y * std::size_t(w) + std::size_t(x)];
                    Rng rng = R.pixel_rng(x, int(y), 0, pass);
                    const float fx = float(x) + rng.uniform(), fy = float(y) + rng.uniform();
                    Hit hit;
                    s.has_point = false;
                    if (!scene.intersect_camera(cam.ray_origin(), cam.ray_direction(fx, fy), hit)) continue;
                    bool unused = false;
                    s.direct += R.emitted_and_direct(hit, c, &unused, pass);
                    const Vec3f albedo = scene.albedo(hit.tri);
                    if (!photons_needed || !(max_component(albedo) > 0)) continue;
                    Vec3f f = albedo * float(1.0 / M_PI);
                    if (prog.final_gather) {
                        // Cosine sampling: f_r cos / pdf = albedo. The bounce's emission is the
                        // first hit's direct light, already sampled; its direct light is added
                        // here and its photons are gathered below.
                        const Vec3f d = sample_cosine(hit.n, rng.uniform(), rng.uniform());
                        const Vec3f o = hit.p + hit.n * scene.epsilon();
                        Hit next;
                        if (!scene.intersect(o, d, next)) continue;
                        const Vec3f next_albedo = scene.albedo(next.tri);
                        if (!(max_component(next_albedo) > 0)) continue;
                        f = albedo * next_albedo * float(1.0 / M_PI);
                        if (settings.direct) s.direct += f * R.direct_irradiance(next, settings.light_samples, c, pass);
                        hit = next;
                    }
                    s.has_point = true;
                    s.p = hit.p;
                    s.normal = hit.n;
                    s.f = f;
                }
            std::lock_guard lock(m);
            Renderer::add(stats.render, c);
        }, settings.threads);
        stats.render.trace_seconds += seconds_since(t0);

        if (photons_needed) {
            t0 = Clock::now();
            const std::vector<Photon> photons =
                trace_photons(scene, settings.photons, settings.seed, settings.threads, nullptr, pass);
            stats.render.photon_seconds += seconds_since(t0);
            stats.render.photons_stored += photons.size();

            t0 = Clock::now();
            float r_max = 0;
            for (const PixelState& s : px)
                if (s.has_point) r_max = std::max(r_max, s.r);
            // One gather pass over either grid; the adaptive grid culls its cells against each
            // pixel's own (shrinking) radius, VR-photon-mapping's grid visits the cells of r_max.
            auto gather_pass = [&](const auto& grid) {
                stats.render.build_seconds += seconds_since(t0);
                t0 = Clock::now();
                const float alpha = prog.alpha;
                const auto detail = k < prog.coarse_passes ? SurfaceDisc::Detail::Coarse : SurfaceDisc::Detail::Fine;
                std::uint64_t gathers = 0;
                parallel_for(npix, 256, [&](std::size_t b, std::size_t e) {
                    std::uint64_t g = 0;
                    for (std::size_t i = b; i < e; ++i) {
                        PixelState& s = px[i];
                        if (!s.has_point) continue;
                        ++g;
                        float found = 0;
                        Vec3f power;
                        if (settings.gather.disc) {
                            // The clipped disc's flux, scaled to the full disc's area so the
                            // final tau / (pi R^2) divides by the area actually gathered.
                            const DiscEstimate d = gather_surface_disc(scene, grid, s.p, s.normal, s.r, detail);
                            const float full = float(M_PI) * s.r * s.r;
                            if (!(d.area > 1e-3f * full)) continue;
                            power = d.power * (full / d.area);
                            found = d.count;
                        } else {
                            power = grid.sum_box(s.p, s.normal, s.r * s.r, &found);
                        }
                        if (!(found > 0)) continue;
                        const double n_new = s.n + alpha * double(found);
                        const double shrink2 = n_new / (s.n + double(found));  // (R' / R)^2
                        s.tau = (s.tau + s.f * power) * float(shrink2);
                        s.r *= float(std::sqrt(shrink2));
                        s.n = n_new;
                    }
                    std::lock_guard lock(m);
                    gathers += g;
                }, settings.threads);
                stats.render.gathers += gathers;
                stats.render.gather_seconds += seconds_since(t0);
            };
            if (r_max > 0 && !photons.empty()) {
                if (settings.grid == GridKind::Adaptive) gather_pass(AdaptiveGrid(photons, r_max));
                else gather_pass(HashGrid(photons, r_max, settings.hash_mode));
            }
        }
        ++k;
        const double elapsed = seconds_since(t_start);
        if (on_pass) {
            resolve(k);
            on_pass(k, img, elapsed);
        }
        if (prog.time_budget > 0 && elapsed >= prog.time_budget) break;
    }
    if (!on_pass) resolve(k);
    stats.passes = k;
    double rsum = 0;
    std::size_t rn = 0;
    for (const PixelState& s : px)
        if (s.n > 0) {
            rsum += s.r;
            ++rn;
        }
    stats.mean_radius = rn ? rsum / double(rn) : double(settings.gather.radius);
    stats.render.total_seconds = seconds_since(t_start);
    return img;
}

}  // namespace gigascroll
