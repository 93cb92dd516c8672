#include "photon/renderer.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numeric>

#include "common/timing.h"
#include "common/error.h"
#include "common/limits.h"
#include "common/parallel.h"
#include "photon/rng.h"

namespace gigascroll {

namespace {
// Hit points per cooperative block (VR-photon-mapping Algorithm 1 uses a thread group).
constexpr std::size_t kCoopBlock = 64;
// Roberts' R2 sequence (the plastic number's additive recurrence): frac(shift + i alpha) is
// well spread in the unit square for any count of points.
constexpr double kPhi2 = 1.3247179572447460;
constexpr double kR2[2] = {1.0 / kPhi2, 1.0 / (kPhi2 * kPhi2)};

inline float r2_coordinate(double shift, int i, int axis) {
    const double x = shift + double(i) * kR2[axis];
    return std::min(float(x - std::floor(x)), 0x1.fffffep-1f);
}
}  // namespace

Pipeline parse_pipeline(const std::string& s) {
    if (s == "fused") return Pipeline::Fused;
    if (s == "two-pass") return Pipeline::TwoPass;
    throw InvalidArgument("pipeline must be 'fused' or 'two-pass', not '" + s + "'");
}

void require_render_size(const Camera& cam, double bytes_per_pixel) {
    const double pixels = double(cam.width) * double(cam.height);
    if (pixels <= double(kMaxRenderPixels)) return;
    throw InvalidArgument("render: a " + std::to_string(cam.width) + " x " + std::to_string(cam.height) +
                          " image would need " + format_bytes(pixels * bytes_per_pixel) +
                          "; at most 2^26 pixels (8192 x 8192) are rendered");
}

void RenderSettings::validate() const {
    require(photons <= kMaxEmittedPhotons, "render: at most 2^32 photons per pass, got " + std::to_string(photons));
    require_threads(threads, "render");
    require(std::isfinite(gather.radius) && gather.radius > 0.0f, "render: radius must be positive and finite");
    require(!indirect || photons > 0, "render: photons must be positive (or switch indirect light off)");
    require(spp >= 1 && spp <= 65536, "render: spp must be in [1, 65536]");
    require(light_samples >= 1 && light_samples <= 4096, "render: light_samples must be in [1, 4096]");
    require(!gather.knn || (gather.k >= 1 && gather.k <= 100000), "render: k must be in [1, 100000]");
    require(!cooperative || pipeline == Pipeline::TwoPass,
            "render: the cooperative gather needs the two-pass pipeline");
    require(!cooperative || grid == GridKind::Hash, "render: the cooperative gather needs the hash grid");
    require(!cooperative || !gather.knn, "render: the cooperative gather is a radius gather (no k-nearest)");
    require(!gather.disc || (!gather.knn && gather.kernel == Kernel::Box && !cooperative),
            "render: the surface disc is a box radius gather (no knn, cone kernel or cooperative gather)");
}

Renderer::Renderer(const Scene& scene, const RenderSettings& settings) : scene_(scene), s_(settings) {
    require(scene.committed(), "render: call Scene.commit() first");
    s_.validate();
    Rng film(s_.seed, stream_id(StreamKind::Pixel, 0, 15), 0);
    film_shift_[0] = film.uniform(), film_shift_[1] = film.uniform();
    const bool need_photons = s_.indirect && scene.emitter_count() > 0 && scene.reflects_anything();
    if (!need_photons) {
        photon_stats_.photon_pass_skipped = true;
        return;
    }
    auto t0 = Clock::now();
    std::vector<Photon> photons = trace_photons(scene, s_.photons, s_.seed, s_.threads);
    photon_stats_.photon_seconds = seconds_since(t0);
    photon_stats_.photons_stored = photons.size();
    t0 = Clock::now();
    map_ = std::make_unique<PhotonMap>(photons, s_.gather.radius, s_.grid, s_.hash_mode);
    photon_stats_.build_seconds = seconds_since(t0);
}

Rng Renderer::pixel_rng(int x, int y, int view, std::uint32_t pass) const {
    return Rng(s_.seed, stream_id(StreamKind::Pixel, pass, std::uint32_t(view)),
               (std::uint64_t(std::uint32_t(y)) << 32) | std::uint32_t(x));
}

void Renderer::film_sample(int x, int y, int s, Rng& rng, float& px, float& py) const {
    if (s_.spp == 1) {  // jittered per pixel
        px = float(x) + rng.uniform(), py = float(y) + rng.uniform();
        return;
    }
    // The same stratified pattern in every pixel, randomly placed once per image (unbiased
    // over the shift; with independent jitter a light's straight edge came out notched: at
    // 4 spp an edge pixel saw 0, 1, 2... of the samples hit a light 60 times brighter than
    // the ceiling beside it).
    px = float(x) + r2_coordinate(film_shift_[0], s, 0);
    py = float(y) + r2_coordinate(film_shift_[1], s, 1);
}

void Renderer::add(RenderStats& st, const ShadeCounters& c) {
    st.gathers += c.gathers;
    st.gathers_skipped += c.gathers_skipped;
    st.shadow_rays += c.shadow_rays;
    st.shadow_rays_skipped += c.shadow_rays_skipped;
}

Vec3f Renderer::emitted_and_direct(const Hit& hit, ShadeCounters& c, bool* needs_gather,
                                   std::uint32_t pass) const {
    Vec3f L = hit.front ? scene_.emission(hit.tri) : Vec3f(0, 0, 0);
    const Vec3f albedo = scene_.albedo(hit.tri);
    const bool reflects = max_component(albedo) > 0;
    *needs_gather = reflects && map_ && map_->size() > 0;
    if (!(reflects && map_ && map_->size() > 0)) ++c.gathers_skipped;
    if (!reflects || !s_.direct || scene_.emitter_count() == 0) return L;

    return L + albedo * kInvPi * direct_irradiance(hit, s_.light_samples, c, pass, true);
}

Vec3f Renderer::direct_irradiance(const Hit& hit, int samples, ShadeCounters& c,
                                  std::uint32_t pass, bool stratified) const {
    if (scene_.emitter_count() == 0 || samples <= 0) return {0, 0, 0};
    Vec3f E{0, 0, 0};
    // Keyed by position, not pixel: both stereo eyes draw the same samples at one point.
    Rng rng(s_.seed, stream_id(StreamKind::Light, pass), scene_.position_key(hit.p));
    if (samples == 1 || !stratified) {
        for (int i = 0; i < samples; ++i) {
            const float ut = rng.uniform(), u1 = rng.uniform(), u2 = rng.uniform();
            E += emitter_sample_irradiance(scene_, hit, scene_.sample_emitter(ut, u1, u2), c);
        }
        return E * (1.0f / float(samples));
    }
    // Stratified: the emitter choice in `samples` equal strata, the point on the triangle
    // from a randomly shifted R2 lattice through the square-root map (area-preserving and
    // continuous, so the points stay spread). Each sample is uniform: unbiased. Independent
    // samples left salt-and-pepper noise wherever a surface sees part of a light at a grazing
    // angle (the Cornell box's tall block: half its samples fall behind its plane).
    const double shift[3] = {rng.uniform(), rng.uniform(), rng.uniform()};
    for (int i = 0; i < samples; ++i) {
        const float ut = std::min(float((double(i) + shift[0]) / double(samples)), 0x1.fffffep-1f);
        const float su = std::sqrt(r2_coordinate(shift[1], i, 0));
        const float u2 = r2_coordinate(shift[2], i, 1);
        E += emitter_sample_irradiance(scene_, hit, scene_.sample_emitter(ut, 1.0f - su, u2 * su), c);
    }
    return E * (1.0f / float(samples));
}

bool emitter_sample_unshadowed(const Scene& scene, const Hit& hit, const LightSample& ls, ShadeCounters& c,
                               EmitterShadowRay& ray) {
    const Vec3f w = ls.p - hit.p;
    const float d2 = dot(w, w);
    const float cos_x = dot(hit.n, w), cos_l = -dot(ls.n, w);
    if (!(cos_x > 0 && cos_l > 0 && d2 > 0)) {  // light behind the surface, or facing away
        ++c.shadow_rays_skipped;
        return false;
    }
    ++c.shadow_rays;
    const float eps = scene.epsilon();
    // cos_x cos_l / d^2 with both cosines still scaled by d.
    ray.contribution = ls.radiance * (cos_x * cos_l / (d2 * d2 * ls.pdf_area));
    ray.origin = hit.p + hit.n * eps;
    ray.direction = ls.p - ray.origin;
    ray.tfar = 1.0f - 2.0f * eps / std::sqrt(d2);
    return true;
}

Vec3f emitter_sample_irradiance(const Scene& scene, const Hit& hit, const LightSample& ls,
                                ShadeCounters& c) {
    EmitterShadowRay ray;
    if (!emitter_sample_unshadowed(scene, hit, ls, c, ray) || scene.occluded(ray.origin, ray.direction, ray.tfar))
        return {0, 0, 0};
    return ray.contribution;
}

Vec3f Renderer::surface_radiance(const Hit& hit, KnnHeap& heap, ShadeCounters& c) const {
    bool gather = false;
    Vec3f L = emitted_and_direct(hit, c, &gather);
    if (gather) {
        ++c.gathers;
        L += scene_.albedo(hit.tri) * kInvPi * indirect_density(hit.p, hit.n, heap);
    }
    return L;
}

Vec3f Renderer::indirect_density(Vec3f p, Vec3f n, KnnHeap& heap) const {
    if (!s_.gather.disc) return map_->gather(p, n, s_.gather, heap);
    const DiscEstimate e = map_->gather_surface_disc(scene_, p, n, s_.gather.radius);
    // A disc clipped to (almost) nothing carries no usable estimate.
    const float r2 = s_.gather.radius * s_.gather.radius;
    if (!(e.area > 1e-3f * float(M_PI) * r2)) return {0, 0, 0};
    return e.power * (1.0f / e.area);
}

std::vector<float> Renderer::render(const Camera& cam, RenderStats& st) const {
    const auto t0 = Clock::now();
    st = photon_stats_;
    require_render_size(cam);
    std::vector<float> img(std::size_t(int(cam.width)) * int(cam.height) * 3, 0.0f);
    if (s_.pipeline == Pipeline::Fused) render_fused(cam, img, st);
    else render_two_pass(cam, img, st);
    st.total_seconds = seconds_since(t0) + photon_stats_.photon_seconds + photon_stats_.build_seconds;
    return img;
}

void Renderer::render_fused(const Camera& cam, std::vector<float>& img, RenderStats& st) const {
    const auto t0 = Clock::now();
    const int w = int(cam.width), h = int(cam.height);
    std::mutex m;
    parallel_for(std::size_t(h), 4, [&](std::size_t yb, std::size_t ye) {
        KnnHeap heap;
        ShadeCounters c;
        for (std::size_t y = yb; y < ye; ++y)
            for (int x = 0; x < w; ++x) {
                Rng rng = pixel_rng(x, int(y), 0);
                Vec3f sum{0, 0, 0};
                for (int s = 0; s < s_.spp; ++s) {
                    float px, py;
                    film_sample(x, int(y), s, rng, px, py);
                    Hit hit;
                    if (scene_.intersect_camera(cam.ray_origin(), cam.ray_direction(px, py), hit))
                        sum += surface_radiance(hit, heap, c);
                    else
                        ++c.gathers_skipped;
                }
                float* out = &img[(y * std::size_t(w) + std::size_t(x)) * 3];
                const Vec3f v = sum / float(s_.spp);
                out[0] = v.x; out[1] = v.y; out[2] = v.z;
            }
        std::lock_guard lock(m);
        add(st, c);
    }, s_.threads);
    // The fused pass does both; report it all as gather time so pipelines compare by total.
    st.gather_seconds = seconds_since(t0);
}

namespace {
// A cooperative block's hit points as structure of arrays, with their flux sums.
struct CoopBlock {
    float x[kCoopBlock], y[kCoopBlock], z[kCoopBlock], nx[kCoopBlock], ny[kCoopBlock], nz[kCoopBlock];
    float r[kCoopBlock], g[kCoopBlock], b[kCoopBlock];
};

// VR-photon-mapping Algorithm 1 on a CPU: each photon of the cell's 27-cell neighbourhood is read once
// and streamed through all hit points of the block. The inner loop is branch-free over the
// block's arrays so the compiler vectorises it (the box kernel; the cone needs a sqrt).
template <bool Cone>
void gather_block(const std::vector<Photon>& photons, const PhotonRun* runs, int nr, CoopBlock& b,
                  std::size_t count, float r2) {
    const float inv_r2 = 1.0f / r2;
    for (int ri = 0; ri < nr; ++ri)
        for (std::uint64_t pi = runs[ri].begin; pi < runs[ri].end; ++pi) {
            const Photon& ph = photons[pi];
            const float px = ph.p.x, py = ph.p.y, pz = ph.p.z, qx = ph.n.x, qy = ph.n.y, qz = ph.n.z;
            const float pr = ph.power.x, pg = ph.power.y, pb = ph.power.z;
            for (std::size_t j = 0; j < count; ++j) {
                const float dx = px - b.x[j], dy = py - b.y[j], dz = pz - b.z[j];
                const float d2 = dx * dx + dy * dy + dz * dz;
                const float agree = qx * b.nx[j] + qy * b.ny[j] + qz * b.nz[j];
                float w = float((d2 <= r2) & (agree > kNormalAgreement));
                if constexpr (Cone) w *= 1.0f - std::sqrt(std::min(d2 * inv_r2, 1.0f));
                b.r[j] += w * pr;
                b.g[j] += w * pg;
                b.b[j] += w * pb;
            }
        }
}

struct HitPoint {
    Vec3f p, n;
    Vec3f weight;  // albedo / pi / spp
    std::uint32_t pixel;
    std::uint64_t key;
};
}  // namespace

void Renderer::render_two_pass(const Camera& cam, std::vector<float>& img, RenderStats& st) const {
    const int w = int(cam.width), h = int(cam.height);
    const float inv_spp = 1.0f / float(s_.spp);
    // Sort key: the hash grid's own cell order, or cells of edge r over the scene for the kd-tree.
    const HashGrid* grid = map_ ? map_->grid() : nullptr;
    const Vec3f lo = scene_.bounds_min();
    const float inv_r = 1.0f / s_.gather.radius;
    const Vec3f ext = scene_.bounds_max() - lo;
    const std::uint64_t gx = std::uint64_t(std::min(ext.x * inv_r + 2.0f, 2097152.0f));
    const std::uint64_t gy = std::uint64_t(std::min(ext.y * inv_r + 2.0f, 2097152.0f));
    auto sort_key = [&](Vec3f p) -> std::uint64_t {
        std::int64_t c[3];
        if (grid) {
            grid->cell_of(p, c);
            return grid->cell_order(c);
        }
        std::uint64_t k[3];
        for (int a = 0; a < 3; ++a)
            k[a] = std::uint64_t(std::clamp((p[a] - lo[a]) * inv_r, 0.0f, 2097151.0f));
        return (k[2] * gy + k[1]) * gx + k[0];
    };

    // Pass 1: primary rays, emission and direct light; keep the hit points that need a gather.
    auto t0 = Clock::now();
    const std::size_t rows_per_chunk = 4;
    const std::size_t chunks = (std::size_t(h) + rows_per_chunk - 1) / rows_per_chunk;
    std::vector<std::vector<HitPoint>> parts(chunks);
    std::mutex m;
    parallel_for(chunks, 1, [&](std::size_t cb, std::size_t ce) {
        ShadeCounters c;
        for (std::size_t ch = cb; ch < ce; ++ch) {
            auto& part = parts[ch];
            const std::size_t ye = std::min(std::size_t(h), (ch + 1) * rows_per_chunk);
            for (std::size_t y = ch * rows_per_chunk; y < ye; ++y)
                for (int x = 0; x < w; ++x) {
                    Rng rng = pixel_rng(x, int(y), 0);
                    const auto pixel = std::uint32_t(y * std::size_t(w) + std::size_t(x));
                    Vec3f sum{0, 0, 0};
                    for (int s = 0; s < s_.spp; ++s) {
                        float px, py;
                        film_sample(x, int(y), s, rng, px, py);
                        Hit hit;
                        if (!scene_.intersect_camera(cam.ray_origin(), cam.ray_direction(px, py), hit)) {
                            ++c.gathers_skipped;
                            continue;
                        }
                        bool gather = false;
                        sum += emitted_and_direct(hit, c, &gather);
                        if (gather)
                            part.push_back({hit.p, hit.n, scene_.albedo(hit.tri) * (kInvPi * inv_spp), pixel,
                                            sort_key(hit.p)});
                    }
                    const Vec3f v = sum * inv_spp;
                    float* out = &img[std::size_t(pixel) * 3];
                    out[0] = v.x; out[1] = v.y; out[2] = v.z;
                }
        }
        std::lock_guard lock(m);
        add(st, c);
    }, s_.threads);
    std::vector<HitPoint> hits;
    {
        std::size_t n = 0;
        for (const auto& p : parts) n += p.size();
        hits.reserve(n);
        for (auto& p : parts) hits.insert(hits.end(), p.begin(), p.end());
    }
    st.trace_seconds = seconds_since(t0);

    // Pass 2: gathers over the hit points in cell order.
    t0 = Clock::now();
    std::sort(hits.begin(), hits.end(), [](const HitPoint& a, const HitPoint& b) {
        return a.key < b.key || (a.key == b.key && a.pixel < b.pixel);
    });
    std::vector<Vec3f> result(hits.size());
    st.gathers += hits.size();
    if (!s_.cooperative) {
        parallel_for(hits.size(), 256, [&](std::size_t b, std::size_t e) {
            KnnHeap heap;
            for (std::size_t i = b; i < e; ++i) result[i] = indirect_density(hits[i].p, hits[i].n, heap);
        }, s_.threads);
    } else {
        // Blocks: runs of at most kCoopBlock hit points in one grid cell (equal keys).
        std::vector<std::size_t> block_start;
        for (std::size_t i = 0; i < hits.size(); ++i)
            if (i == 0 || hits[i].key != hits[i - 1].key || i - block_start.back() >= kCoopBlock)
                block_start.push_back(i);
        block_start.push_back(hits.size());
        const float r = s_.gather.radius, r2 = r * r;
        const Kernel kernel = s_.gather.kernel;
        const float scale = 1.0f / (kernel_norm(kernel) * float(M_PI) * r2);
        const std::vector<Photon>& photons = grid->photons();
        parallel_for(block_start.size() - 1, 16, [&](std::size_t bb, std::size_t be) {
            CoopBlock b;
            for (std::size_t blk = bb; blk < be; ++blk) {
                const std::size_t first = block_start[blk], count = block_start[blk + 1] - first;
                for (std::size_t j = 0; j < count; ++j) {
                    const HitPoint& hp = hits[first + j];
                    b.x[j] = hp.p.x; b.y[j] = hp.p.y; b.z[j] = hp.p.z;
                    b.nx[j] = hp.n.x; b.ny[j] = hp.n.y; b.nz[j] = hp.n.z;
                    b.r[j] = b.g[j] = b.b[j] = 0.0f;
                }
                PhotonRun runs[27];
                const int nr = grid->runs(hits[first].p, runs);  // the same for the whole cell
                if (kernel == Kernel::Cone) gather_block<true>(photons, runs, nr, b, count, r2);
                else gather_block<false>(photons, runs, nr, b, count, r2);
                for (std::size_t j = 0; j < count; ++j) result[first + j] = Vec3f(b.r[j], b.g[j], b.b[j]) * scale;
            }
        }, s_.threads);
    }
    // Accumulate serially: a pixel's samples may sit in different blocks.
    for (std::size_t i = 0; i < hits.size(); ++i) {
        float* out = &img[std::size_t(hits[i].pixel) * 3];
        const Vec3f v = hits[i].weight * result[i];
        out[0] += v.x; out[1] += v.y; out[2] += v.z;
    }
    st.gather_seconds = seconds_since(t0);
}

}  // namespace gigascroll
