#include "photon/stereo.h"

#include <atomic>
#include <memory>
#include <mutex>

#include "common/timing.h"
#include "common/error.h"
#include "common/parallel.h"
#include "photon/rng.h"

namespace gigascroll {

StereoImages render_stereo(const Renderer& R, const StereoCamera& eyes, bool reuse, bool keep_sources) {
    require(R.settings().pipeline == Pipeline::Fused, "render_stereo: stereo reuse renders with the fused pipeline");
    const Camera& L = eyes.left;
    const Camera& Rt = eyes.right;
    require_render_size(L, 2 * 12);
    const int w = int(L.width), h = int(L.height);
    const std::size_t n = std::size_t(w) * std::size_t(h);
    const int spp = R.settings().spp;
    const Scene& scene = R.scene();
    const float eps = scene.epsilon();
    StereoImages out;
    out.left.assign(n * 3, 0.0f);
    out.right.assign(n * 3, 0.0f);
    if (keep_sources) out.sources.assign(n, Hit{});
    // claimed[i] goes 0 -> 1 once, by the left-eye sample that wins the CAS; only that sample
    // then writes right[i]. Relaxed order suffices: the right pass reads claimed and right only
    // after parallel_for has joined every left-eye thread, and the join orders those writes
    // before the reads.
    std::unique_ptr<std::atomic<std::uint32_t>[]> claimed(new std::atomic<std::uint32_t>[n]);
    for (std::size_t i = 0; i < n; ++i) claimed[i].store(0, std::memory_order_relaxed);

    const auto t_all = Clock::now();
    out.left_stats = R.photon_stats();
    out.right_stats = R.photon_stats();
    std::mutex m;
    auto t0 = Clock::now();
    const Vec3f right_eye = Rt.ray_origin();
    std::atomic<std::uint64_t> reused{0};
    parallel_for(std::size_t(h), 4, [&](std::size_t yb, std::size_t ye) {
        KnnHeap heap;
        ShadeCounters c;
        std::uint64_t won = 0;
        for (std::size_t y = yb; y < ye; ++y)
            for (int x = 0; x < w; ++x) {
                Rng rng = R.pixel_rng(x, int(y), 0);
                Vec3f sum{0, 0, 0};
                for (int s = 0; s < spp; ++s) {
                    float px, py;
                    R.film_sample(x, int(y), s, rng, px, py);
                    Hit hit;
                    if (!scene.intersect_camera(L.ray_origin(), L.ray_direction(px, py), hit)) continue;
                    const Vec3f col = R.surface_radiance(hit, heap, c);
                    sum += col;
                    if (!reuse) continue;
                    int rx, ry;
                    const Vec3f to_eye = right_eye - hit.p;
                    if (dot(to_eye, hit.n) <= 0 || !Rt.project(hit.p, rx, ry)) continue;
                    const std::size_t ri = std::size_t(ry) * std::size_t(w) + std::size_t(rx);
                    if (claimed[ri].load(std::memory_order_relaxed) != 0) continue;  // cheap early out
                    const Vec3f o = hit.p + hit.n * eps;
                    if (scene.occluded(o, right_eye - o, 1.0f)) continue;
                    std::uint32_t expected = 0;
                    if (!claimed[ri].compare_exchange_strong(expected, 1, std::memory_order_relaxed)) continue;
                    float* dst = &out.right[ri * 3];
                    dst[0] = col.x; dst[1] = col.y; dst[2] = col.z;
                    if (keep_sources) out.sources[ri] = hit;
                    ++won;
                }
                const Vec3f v = sum / float(spp);
                float* dst = &out.left[(y * std::size_t(w) + std::size_t(x)) * 3];
                dst[0] = v.x; dst[1] = v.y; dst[2] = v.z;
            }
        reused.fetch_add(won, std::memory_order_relaxed);
        std::lock_guard lock(m);
        Renderer::add(out.left_stats, c);
    }, R.settings().threads);
    out.left_stats.gather_seconds = seconds_since(t0);
    out.left_stats.total_seconds = out.left_stats.gather_seconds;

    // Right eye: only the unclaimed pixels.
    t0 = Clock::now();
    parallel_for(std::size_t(h), 4, [&](std::size_t yb, std::size_t ye) {
        KnnHeap heap;
        ShadeCounters c;
        for (std::size_t y = yb; y < ye; ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t i = y * std::size_t(w) + std::size_t(x);
                if (claimed[i].load(std::memory_order_relaxed) != 0) continue;
                Rng rng = R.pixel_rng(x, int(y), 1);
                Vec3f sum{0, 0, 0};
                for (int s = 0; s < spp; ++s) {
                    float px, py;
                    R.film_sample(x, int(y), s, rng, px, py);
                    Hit hit;
                    if (scene.intersect_camera(Rt.ray_origin(), Rt.ray_direction(px, py), hit))
                        sum += R.surface_radiance(hit, heap, c);
                }
                const Vec3f v = sum / float(spp);
                float* dst = &out.right[i * 3];
                dst[0] = v.x; dst[1] = v.y; dst[2] = v.z;
            }
        std::lock_guard lock(m);
        Renderer::add(out.right_stats, c);
    }, R.settings().threads);
    out.right_stats.gather_seconds = seconds_since(t0);
    out.right_stats.total_seconds = out.right_stats.gather_seconds;
    out.right_stats.reused_pixels = reused.load();
    out.left_stats.reused_pixels = reused.load();
    out.total_seconds = seconds_since(t_all) + R.photon_stats().photon_seconds + R.photon_stats().build_seconds;
    return out;
}

}  // namespace gigascroll
