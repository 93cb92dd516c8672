#include "sampling/stereo_display.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include "common/timing.h"
#include "common/error.h"
#include "common/parallel.h"
#include "sampling/sampler.h"
#include "views/feedback.h"

namespace gigascroll {

namespace {
constexpr unsigned kNoHit = RTC_INVALID_GEOMETRY_ID;
constexpr std::uint64_t kUnclaimed = ~std::uint64_t(0);

// sRGB-encoded 0..255 to linear [0, 1] (IEC 61966-2-1): the exact curve tabulated every 1/16
// of a code and interpolated linearly (the filtered value is not an integer). Three pow()
// calls per pixel were a third of the shading; the table's error is below 1e-7.
struct SrgbTable {
    static constexpr int kSteps = 16;
    SrgbTable() {
        for (int i = 0; i <= 255 * kSteps + 1; ++i) {
            const double c = std::min(double(i) / kSteps, 255.0) / 255.0;
            value[std::size_t(i)] = float(c <= 0.04045 ? c / 12.92 : std::pow((c + 0.055) / 1.055, 2.4));
        }
    }
    float operator()(float code) const {
        const float x = std::clamp(code, 0.0f, 255.0f) * kSteps;
        const int i = int(x);
        const float f = x - float(i);
        return value[std::size_t(i)] + f * (value[std::size_t(i) + 1] - value[std::size_t(i)]);
    }
    std::array<float, 255 * kSteps + 2> value;
};
const SrgbTable& srgb_table() {
    static const SrgbTable table;
    return table;
}

// Casts the primary rays of rows [row_begin, row_end) in 16-ray packets along each row; a
// pixel with skip[i] != 0 is left out of its packet. on_packet(row, i0, n, packet) sees
// each packet after Embree filled it.
template <typename OnPacket>
void cast_rows(RTCScene scene, const Camera& eye, std::size_t row_begin, std::size_t row_end,
               const std::uint8_t* skip, OnPacket&& on_packet) {
    const std::uint32_t w = eye.width;
    const std::size_t padded = (std::size_t(w) + 15) / 16 * 16;
    std::vector<float> dir_x(padded), dir_y(padded), dir_z(padded);
    std::vector<double> column_sx(padded);
    for (std::uint32_t i = 0; i < w; ++i) column_sx[i] = eye.screen_x(i + 0.5);
    std::fill(column_sx.begin() + w, column_sx.end(), column_sx[w - 1]);
    RTCRayHit16 packet;
    for (std::uint32_t k = 0; k < 16; ++k) {
        packet.ray.org_x[k] = float(eye.position.x), packet.ray.org_y[k] = float(eye.position.y);
        packet.ray.org_z[k] = float(eye.position.z);
        packet.ray.tnear[k] = 0.f, packet.ray.time[k] = 0.f, packet.ray.mask[k] = ~0u;
        packet.ray.id[k] = k, packet.ray.flags[k] = 0;
        packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
    }
    for (std::size_t row = row_begin; row < row_end; ++row) {
        const Vec3d row_dir = eye.forward + eye.screen_y(row + 0.5) * eye.up;
        for (std::size_t i = 0; i < padded; ++i) {
            const double c = column_sx[i];
            dir_x[i] = float(row_dir.x + c * eye.right.x);
            dir_y[i] = float(row_dir.y + c * eye.right.y);
            dir_z[i] = float(row_dir.z + c * eye.right.z);
        }
        const std::uint8_t* row_skip = skip ? skip + row * w : nullptr;
        for (std::uint32_t i0 = 0; i0 < w; i0 += 16) {
            const std::uint32_t n = std::min<std::uint32_t>(16, w - i0);
            alignas(64) int valid[16];
            bool any = false;
            for (std::uint32_t k = 0; k < 16; ++k) {
                valid[k] = k < n && !(row_skip && row_skip[i0 + k]) ? -1 : 0;
                any |= valid[k] != 0;
                packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
                packet.hit.geomID[k] = kNoHit;
            }
            if (!any) continue;
            std::memcpy(packet.ray.dir_x, dir_x.data() + i0, sizeof packet.ray.dir_x);
            std::memcpy(packet.ray.dir_y, dir_y.data() + i0, sizeof packet.ray.dir_y);
            std::memcpy(packet.ray.dir_z, dir_z.data() + i0, sizeof packet.ray.dir_z);
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            rtcIntersect16(valid, scene, &context, &packet);
            on_packet(row, i0, n, valid, packet);
        }
    }
}

void check_camera(const Camera& eye) {
    require(eye.width > 0 && eye.height > 0, "display: the eye's resolution must be positive");
    require(std::uint64_t(eye.width) * eye.height < (std::uint64_t(1) << 31),
            "display: at most 2^31 pixels per eye");
}
}  // namespace

void DisplayPass::GBuffer::resize(std::uint32_t w, std::uint32_t h) {
    width = w, height = h;
    const std::size_t n = std::size_t(w) * h;
    geom.resize(n), prim.resize(n), p.resize(n);
    this->n.resize(n), uv.resize(2 * n), lod.resize(n), placement.resize(n), albedo.resize(3 * n);
    light.resize(n), copied.resize(n);
}

void DisplayPass::trace(const PaintingSceneView& scene, const Camera& eye, GBuffer& g,
                        const std::uint8_t* skip, unsigned threads, EyeStats& st) {
    const auto t0 = Clock::now();
    const std::uint32_t w = eye.width;
    const Vec3f o(eye.position);
    std::atomic<std::uint64_t> traced{0};
    parallel_for(eye.height, 4, [&](std::size_t rb, std::size_t re) {
        std::uint64_t count = 0;
        cast_rows(scene.handle, eye, rb, re, skip, [&](std::size_t row, std::uint32_t i0,
                                                       std::uint32_t n, const int* valid,
                                                       const RTCRayHit16& h) {
            for (std::uint32_t k = 0; k < n; ++k) {
                if (!valid[k]) continue;
                ++count;
                const std::size_t i = row * w + i0 + k;
                const unsigned geom = h.hit.geomID[k];
                g.geom[i] = geom;
                if (geom == kNoHit) continue;
                g.prim[i] = h.hit.primID[k];
                const Vec3f d{h.ray.dir_x[k], h.ray.dir_y[k], h.ray.dir_z[k]};
                g.p[i] = o + d * h.ray.tfar[k];
                Vec3f ng{h.hit.Ng_x[k], h.hit.Ng_y[k], h.hit.Ng_z[k]};
                ng = ng / std::sqrt(dot(ng, ng));
                g.n[i] = dot(ng, d) > 0 ? -ng : ng;  // two-sided: the side the eye sees
            }
        });
        traced.fetch_add(count, std::memory_order_relaxed);
    }, threads);
    st.traced = traced.load();
    st.rays_seconds = seconds_since(t0);
}

void DisplayPass::sample(const PaintingSceneView& scene, const VirtualTexture& vt,
                         const Camera& eye, GBuffer& g, const GBuffer* source,
                         const std::int32_t* reused, const DisplayOptions& o, EyeStats& st) {
    const auto t0 = Clock::now();
    const std::uint32_t w = g.width;
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    const std::size_t paintings = vt.layout().paintings.size();
    std::atomic<std::uint64_t> on_paintings{0}, hits{0};
    parallel_for(g.height, 8, [&](std::size_t rb, std::size_t re) {
        std::uint64_t count = 0, hit_count = 0;
        for (std::size_t row = rb; row < re; ++row) {
            // Level of detail and painting coordinates from the hit point, so a reused
            // point gets the level of the eye that displays it.
            for (std::uint32_t x = 0; x < w; ++x) {
                const std::size_t i = row * w + x;
                g.placement[i] = -1;
                g.lod[i] = kNaN;
                g.copied[i] = 0;
                if (g.geom[i] == kNoHit) continue;
                ++hit_count;
                const int pl = scene.placement_of(g.geom[i]);
                if (pl < 0) continue;
                const PaintingPlacement& pp = scene.paintings[std::size_t(pl)];
                // A traced pixel: the plane point of its centre's ray in double (a 12 m scroll
                // of 150k texels needs more than float); a reused one: the left eye's point,
                // seen from this eye.
                Vec3d dd;
                double t;
                if (reused && reused[i] >= 0) {
                    const Vec3d to_p = Vec3d(g.p[i]) - eye.position;
                    t = dot(to_p, eye.forward);
                    if (!(t > 0)) continue;
                    dd = to_p / t;
                } else {
                    dd = eye.direction(x + 0.5, row + 0.5);
                    t = dot(pp.origin - eye.position, pp.normal()) / dot(dd, pp.normal());
                }
                const Vec3d rel = eye.position + t * dd - pp.origin;
                const double u = std::clamp(dot(rel, pp.u_axis) / pp.width_m, 0.0, 1.0);
                const double v = std::clamp(dot(rel, pp.v_axis) / pp.height_m, 0.0, 1.0);
                const double rho = texel_footprint(pp, eye, dd, t);
                g.placement[i] = pl;
                g.uv[2 * i] = u, g.uv[2 * i + 1] = v;
                g.lod[i] = float(std::log2(rho)) + o.lod_bias;
                if (!std::isfinite(g.lod[i])) g.lod[i] = 0.0f;
                ++count;
                // A reused point whose level here is the left eye's to within the tolerance
                // keeps the left eye's sample (the trilinear blend would move by less than
                // that fraction of the two levels' difference).
                if (source && reused && reused[i] >= 0) {
                    const std::size_t s = std::size_t(reused[i]);
                    if (source->placement[s] == pl &&
                        std::abs(source->lod[s] - g.lod[i]) <= o.reuse_lod_tolerance) {
                        std::copy_n(&source->albedo[3 * s], 3, &g.albedo[3 * i]);
                        g.copied[i] = 1;
                    }
                }
            }
            // Runs of one painting sampled in one call (copied samples end a run).
            for (std::uint32_t j0 = 0; j0 < w;) {
                const std::size_t i0 = row * w + j0;
                const int pl = g.copied[i0] ? -1 : g.placement[i0];
                std::uint32_t j1 = j0 + 1;
                while (j1 < w && !g.copied[row * w + j1] && g.placement[row * w + j1] == pl) ++j1;
                if (pl >= 0) {
                    const std::size_t i = row * w + j0;
                    SampleRequest r;
                    r.painting = scene.paintings[std::size_t(pl)].painting;
                    require(r.painting < paintings, "display: a painting of the scene is not in "
                                                    "the virtual texture");
                    r.u = &g.uv[2 * i], r.v = r.u + 1, r.uv_stride = 2;
                    r.lod = &g.lod[i];
                    r.count = j1 - j0;
                    r.filter = Filter::Trilinear;
                    r.out = &g.albedo[3 * i];
                    sample_serial(vt, r);
                }
                j0 = j1;
            }
        }
        on_paintings.fetch_add(count, std::memory_order_relaxed);
        hits.fetch_add(hit_count, std::memory_order_relaxed);
    }, o.threads);
    st.painting_pixels = on_paintings.load();
    st.hits = hits.load();
    st.vt_seconds = seconds_since(t0);
}

void DisplayPass::shade(const DisplayLighting& lighting, GBuffer& g, const GBuffer* source,
                        const std::int32_t* reused, const DisplayOptions& o, float* rgb,
                        EyeStats& st) {
    const auto t0 = Clock::now();
    const std::size_t n = std::size_t(g.width) * g.height;
    const SrgbTable& srgb_decode = srgb_table();
    parallel_for(n, 4096, [&](std::size_t b, std::size_t e) {
        SurfaceLight sl;
        for (std::size_t i = b; i < e; ++i) {
            float* out = rgb + 3 * i;
            if (g.geom[i] == kNoHit) {
                out[0] = out[1] = out[2] = 0.0f;
                continue;
            }
            // A reused point's light is the left eye's: irradiance, albedo and emission do
            // not depend on the eye (Lambertian surfaces, same side).
            if (source && reused && reused[i] >= 0) {
                sl = source->light[std::size_t(reused[i])];
            } else {
                lighting.light(g.geom[i], g.prim[i], g.p[i], g.n[i], sl);
            }
            g.light[i] = sl;
            // The Gallery's order of operations (its sRGB curve is exact, ours tabulated).
            Vec3f L;
            if (g.placement[i] >= 0) {
                const float* a = &g.albedo[3 * i];
                const Vec3f albedo =
                    (o.srgb_albedo ? Vec3f{srgb_decode(a[0]), srgb_decode(a[1]), srgb_decode(a[2])}
                                   : Vec3f{a[0], a[1], a[2]} * (1.0f / 255.0f)) *
                    o.painting_reflectance;
                L = albedo * (sl.irradiance * kInvPi) + sl.emission;
            } else {
                L = sl.albedo * sl.irradiance * kInvPi + sl.emission;
            }
            out[0] = L.x, out[1] = L.y, out[2] = L.z;
        }
    }, o.threads);
    st.shade_seconds = seconds_since(t0);
}

void DisplayPass::reuse(const Camera& right, const DisplayOptions& o, EyeStats& st) {
    const auto t0 = Clock::now();
    const GBuffer& L = g_[0];
    GBuffer& R = g_[1];
    const std::size_t n = std::size_t(R.width) * R.height;
    claims_.assign(n, kUnclaimed);
    const Vec3f eye(right.position), fwd(right.forward);
    // Claims: the nearest left hit per right pixel wins (depth in the high word, so the
    // smaller 64-bit value is the nearer claim; positive floats order as their bits).
    parallel_for(L.geom.size(), 4096, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) {
            if (L.geom[i] == kNoHit) continue;
            const Vec3f p = L.p[i], to_eye = eye - p;
            if (dot(to_eye, L.n[i]) <= 0) continue;  // the right eye sees the other side
            int rx, ry;
            if (!right.project(p, rx, ry)) continue;
            const float depth = dot(p - eye, fwd);
            if (!(depth > 0)) continue;
            const std::uint64_t claim =
                (std::uint64_t(std::bit_cast<std::uint32_t>(depth)) << 32) | std::uint64_t(i);
            std::atomic_ref<std::uint64_t> slot(claims_[std::size_t(ry) * R.width + std::size_t(rx)]);
            std::uint64_t seen = slot.load(std::memory_order_relaxed);
            while (claim < seen &&
                   !slot.compare_exchange_weak(seen, claim, std::memory_order_relaxed)) {
            }
        }
    }, o.threads);
    // Release claims on depth edges, then copy the surviving left hits into the right
    // G-buffer. parallel_for's join orders the claims before these reads.
    claimed_.assign(n, 0);
    sources_.assign(n, -1);
    const float ratio = 1.0f + o.edge_depth_ratio;
    const std::int64_t w = R.width, h = R.height;
    std::atomic<std::uint64_t> reused{0};
    parallel_for(std::size_t(h), 8, [&](std::size_t rb, std::size_t re) {
        std::uint64_t count = 0;
        for (std::int64_t y = std::int64_t(rb); y < std::int64_t(re); ++y)
            for (std::int64_t x = 0; x < w; ++x) {
                const std::size_t i = std::size_t(y * w + x);
                const std::uint64_t c = claims_[i];
                if (c == kUnclaimed) continue;
                const float depth = std::bit_cast<float>(std::uint32_t(c >> 32));
                bool edge = false;
                for (std::int64_t dy = -1; dy <= 1 && !edge; ++dy)
                    for (std::int64_t dx = -1; dx <= 1; ++dx) {
                        const std::int64_t nx = x + dx, ny = y + dy;
                        if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
                        const std::uint64_t nc = claims_[std::size_t(ny * w + nx)];
                        if (nc == kUnclaimed) continue;
                        if (depth > std::bit_cast<float>(std::uint32_t(nc >> 32)) * ratio) {
                            edge = true;
                            break;
                        }
                    }
                if (edge) continue;
                const std::size_t src = std::size_t(c & 0xffffffffu);
                claimed_[i] = 1;
                sources_[i] = std::int32_t(src);
                R.geom[i] = L.geom[src], R.prim[i] = L.prim[src];
                R.p[i] = L.p[src], R.n[i] = L.n[src];
                ++count;
            }
        reused.fetch_add(count, std::memory_order_relaxed);
    }, o.threads);
    st.reused = reused.load();
    st.reuse_seconds = seconds_since(t0);
}

void DisplayPass::render(const PaintingSceneView& scene, const DisplayLighting& lighting,
                         const VirtualTexture& vt, const Camera& eye, const DisplayOptions& o,
                         float* rgb) {
    require(scene.handle != nullptr, "display: the scene has no BVH");
    require(rgb != nullptr, "display: no output image");
    check_camera(eye);
    GBuffer& g = g_[0];
    g.resize(eye.width, eye.height);
    EyeStats& st = stats_[0] = EyeStats{};
    st.pixels = std::uint64_t(eye.width) * eye.height;
    trace(scene, eye, g, nullptr, o.threads, st);
    sample(scene, vt, eye, g, nullptr, nullptr, o, st);
    shade(lighting, g, nullptr, nullptr, o, rgb, st);
    sources_.clear();
}

void DisplayPass::render_stereo(const PaintingSceneView& scene, const DisplayLighting& lighting,
                                const VirtualTexture& vt, const Camera& left, const Camera& right,
                                bool use_reuse, const DisplayOptions& o, float* left_rgb,
                                float* right_rgb) {
    require(scene.handle != nullptr, "display: the scene has no BVH");
    require(left_rgb != nullptr && right_rgb != nullptr, "display: no output image");
    check_camera(left);
    check_camera(right);
    require(left.width == right.width && left.height == right.height,
            "display: both eyes need the same resolution");
    require(std::isfinite(o.edge_depth_ratio) && o.edge_depth_ratio >= 0,
            "display: edge_depth_ratio must be finite and >= 0");
    render(scene, lighting, vt, left, o, left_rgb);
    GBuffer& g = g_[1];
    g.resize(right.width, right.height);
    EyeStats& st = stats_[1] = EyeStats{};
    st.pixels = std::uint64_t(right.width) * right.height;
    if (use_reuse) {
        reuse(right, o, st);
        trace(scene, right, g, claimed_.data(), o.threads, st);
    } else {
        sources_.clear();
        trace(scene, right, g, nullptr, o.threads, st);
    }
    const std::int32_t* reused = use_reuse ? sources_.data() : nullptr;
    sample(scene, vt, right, g, &g_[0], reused, o, st);
    shade(lighting, g, &g_[0], reused, o, right_rgb, st);
}

std::vector<float> DisplayPass::hit_points(int eye) const {
    require(eye == 0 || eye == 1, "eye must be 0 (left) or 1 (right)");
    const GBuffer& g = g_[eye];
    std::vector<float> out(3 * g.geom.size(), std::numeric_limits<float>::quiet_NaN());
    for (std::size_t i = 0; i < g.geom.size(); ++i)
        if (g.geom[i] != kNoHit) out[3 * i] = g.p[i].x, out[3 * i + 1] = g.p[i].y, out[3 * i + 2] = g.p[i].z;
    return out;
}

std::vector<float> DisplayPass::lods(int eye) const {
    require(eye == 0 || eye == 1, "eye must be 0 (left) or 1 (right)");
    return g_[eye].lod;
}

double cast_primary_rays(RTCScene scene, const Camera& eye, unsigned threads, std::uint64_t* hits) {
    require(scene != nullptr, "cast_primary_rays: the scene has no BVH");
    check_camera(eye);
    const auto t0 = Clock::now();
    std::atomic<std::uint64_t> total{0};
    parallel_for(eye.height, 4, [&](std::size_t rb, std::size_t re) {
        std::uint64_t count = 0;
        cast_rows(scene, eye, rb, re, nullptr, [&](std::size_t, std::uint32_t, std::uint32_t n,
                                                   const int*, const RTCRayHit16& h) {
            for (std::uint32_t k = 0; k < n; ++k) count += h.hit.geomID[k] != kNoHit;
        });
        total.fetch_add(count, std::memory_order_relaxed);
    }, threads);
    if (hits) *hits = total.load();
    return seconds_since(t0);
}

}  // namespace gigascroll
