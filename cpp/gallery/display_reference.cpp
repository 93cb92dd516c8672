// Gallery::render_display and its per-pixel path, the display pass's oracle
// (Gallery::DisplayOracle; display/display_pass.h).
// Each pixel by itself in the plainest arithmetic (its ray, its hit, its light solved from the
// point, its painting coordinates in double from the plane, the exact sRGB curve), which the
// fast pass is tested against; with lighting "baked" and nothing but the image asked, the
// display pass itself.
#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
#include <vector>

#include "common/error.h"
#include "common/parallel.h"
#include "display/display_pass.h"
#include "display/srgb.h"
#include "gallery/display_lighting.h"
#include "gallery/gallery.h"
#include "sampling/sampler.h"
#include "views/feedback.h"

namespace gigascroll {

namespace {
// Gallery::barycentric's double arithmetic after its dot products, for m <= 16 points, with
// selects in SIMD lanes (the same operations, so the same values): b1, b2 from the Gram
// terms and the point's dot products, clamped onto the triangle. No trapping math, as in
// lattice_cells, so that GCC evaluates both sides of the selects.
[[gnu::optimize("no-trapping-math"), gnu::noinline]]
void barycentric_solve(std::size_t m, const double* __restrict d00, const double* __restrict d01,
                       const double* __restrict d11, const double* __restrict denom,
                       const double* __restrict d20, const double* __restrict d21, float* __restrict b1_out,
                       float* __restrict b2_out) {
    for (std::size_t k = 0; k < m; ++k) {
        const bool solvable = denom[k] > 0;
        const double q1 = (d11[k] * d20[k] - d01[k] * d21[k]) / denom[k];
        const double q2 = (d00[k] * d21[k] - d01[k] * d20[k]) / denom[k];
        double b1 = solvable ? q1 : 0.0, b2 = solvable ? q2 : 0.0;
        b1 = b1 < 0.0 ? 0.0 : (1.0 < b1 ? 1.0 : b1);  // std::clamp
        b2 = b2 < 0.0 ? 0.0 : (1.0 < b2 ? 1.0 : b2);
        const double s = b1 + b2;
        const bool over = s > 1;
        const double r1 = b1 / s, r2 = b2 / s;
        b1_out[k] = float(over ? r1 : b1), b2_out[k] = float(over ? r2 : b2);
    }
}
}  // namespace

// The per-pixel path of render_display, the display pass's oracle, over one chunk of rows:
// each row's pixels traced in Embree packets of 16 (coherent, as the feedback pass casts
// them), each pixel lit and mapped by itself, then the row's painting pixels sampled (one VT
// call per run of the same painting) and shaded.
struct Gallery::DisplayOracle {
    // A painting pixel waiting for its texels: radiance = albedo * scale + add.
    struct Pending {
        std::uint32_t x;
        int slot;
        Vec3f scale, add;
    };
    const Gallery& g;
    const Camera& camera;  // in the room's coordinates
    const VirtualTexture& vt;
    const Lighting lighting;
    float* const rgb;
    const DisplayHits& hits;
    const Vec3f origin;
    RTCRayHit16 packet;
    std::vector<Pending> pending;
    std::vector<double> uv;
    std::vector<float> lods, texels;
    // The packet being traced: its directions (unnormalised), hits and baked light.
    Vec3d dd16[16];
    Hit hit16[16];
    Vec3f batch_E[16];

    DisplayOracle(const Gallery& gallery, const Camera& cam, const VirtualTexture& texture, Lighting l, float* out,
                  const DisplayHits& h)
        : g(gallery), camera(cam), vt(texture), lighting(l), rgb(out), hits(h), origin(cam.position) {
        for (std::uint32_t k = 0; k < 16; ++k) {
            packet.ray.org_x[k] = origin.x, packet.ray.org_y[k] = origin.y, packet.ray.org_z[k] = origin.z;
            packet.ray.tnear[k] = 0.f;
            packet.ray.time[k] = 0.f;
            packet.ray.mask[k] = ~0u;
            packet.ray.id[k] = k;
            packet.ray.flags[k] = 0;
            packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
    }

    void row(std::size_t y) {
        pending.clear(), uv.clear(), lods.clear();
        const std::uint32_t W = camera.width;
        for (std::uint32_t x0 = 0; x0 < W; x0 += 16) {
            const std::uint32_t n16 = std::min<std::uint32_t>(16, W - x0);
            trace(x0, n16, y);
            if (lighting == Lighting::Baked) bake_light(n16);
            std::size_t batch_next = 0;
            for (std::uint32_t k = 0; k < n16; ++k) pixel(y, x0, k, batch_next);
        }
        paint_row(y);
    }

    // Primary rays of pixels x0 .. x0 + n16 - 1 of row y; the hits then as Scene::intersect
    // reports them.
    void trace(std::uint32_t x0, std::uint32_t n16, std::size_t y) {
        alignas(64) int valid[16];
        for (std::uint32_t k = 0; k < 16; ++k) {
            valid[k] = k < n16 ? -1 : 0;
            dd16[k] = camera.direction(x0 + std::min(k, n16 - 1) + 0.5, y + 0.5);
            const Vec3f d(normalize(dd16[k]));
            packet.ray.dir_x[k] = d.x, packet.ray.dir_y[k] = d.y, packet.ray.dir_z[k] = d.z;
            packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
            packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        }
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
        rtcIntersect16(valid, g.scene_.handle(), &context, &packet);
        for (std::uint32_t k = 0; k < n16; ++k) {
            Hit& hit = hit16[k];
            hit = Hit{};
            if (!found(k)) continue;
            const Vec3f d(packet.ray.dir_x[k], packet.ray.dir_y[k], packet.ray.dir_z[k]);
            hit.t = packet.ray.tfar[k];
            hit.tri = g.geom_first_tri_[packet.hit.geomID[k]] + packet.hit.primID[k];
            hit.p = origin + d * hit.t;
            const Vec3f nn = g.scene_.normal(hit.tri);
            hit.front = dot(nn, d) < 0;
            hit.n = hit.front ? nn : -nn;
        }
    }
    bool found(std::uint32_t k) const { return packet.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID; }

    // Baked: the packet's hits through irradiance_baked_batch (lattice_lerp's operations at
    // the same barycentrics: irradiance_baked's values, without a call and its mispredicted
    // branches per pixel), in the order of the hit pixels.
    void bake_light(std::uint32_t n16) {
        alignas(64) std::uint32_t batch_tri[16];
        alignas(64) float batch_b1[16], batch_b2[16];
        bool batch_front[16];
        alignas(64) double g00[16], g01[16], g11[16], det[16], d20[16], d21[16];
        std::size_t m = 0;
        for (std::uint32_t k = 0; k < n16; ++k) {
            if (!found(k)) continue;
            const std::uint32_t t = hit16[k].tri;
            const Vec3f d = hit16[k].p - g.tri_v0_[t];
            const BarycentricTerms& b = g.tri_terms_[t];
            g00[m] = b.d00, g01[m] = b.d01, g11[m] = b.d11, det[m] = b.denom;
            d20[m] = dot(d, g.tri_e1_[t]), d21[m] = dot(d, g.tri_e2_[t]);
            batch_tri[m] = t, batch_front[m] = hit16[k].front;
            ++m;
        }
        barycentric_solve(m, g00, g01, g11, det, d20, d21, batch_b1, batch_b2);
        g.irradiance_baked_batch(batch_tri, batch_front, batch_b1, batch_b2, m, batch_E);
    }

    // Pixel x0 + k of row y: its hit outputs, and its radiance (a painting pixel's after
    // paint_row); batch_next counts the packet's hit pixels (their baked light).
    void pixel(std::size_t y, std::uint32_t x0, std::uint32_t k, std::size_t& batch_next) {
        constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
        const std::uint32_t x = x0 + k;
        const std::size_t px = y * std::size_t(camera.width) + x;
        float* out = rgb + 3 * px;
        const Hit& hit = hit16[k];
        const int slot = found(k) ? g.tri_slot_[hit.tri] : -1;
        if (hits.position) {
            const Vec3f p = found(k) ? Vec3f(Vec3d(hit.p) + g.origin_) : Vec3f(kNaN, kNaN, kNaN);
            hits.position[3 * px] = p.x, hits.position[3 * px + 1] = p.y, hits.position[3 * px + 2] = p.z;
        }
        if (hits.slot) hits.slot[px] = slot;
        if (!found(k)) {
            out[0] = out[1] = out[2] = 0;
            if (hits.irradiance) hits.irradiance[3 * px] = hits.irradiance[3 * px + 1] = hits.irradiance[3 * px + 2] = 0;
            if (hits.uv) hits.uv[2 * px] = hits.uv[2 * px + 1] = kNaN;
            if (hits.lod) hits.lod[px] = kNaN;
            return;
        }
        Vec3f E;
        switch (lighting) {
            case Lighting::Unlit: E = Vec3f(float(M_PI), float(M_PI), float(M_PI)); break;
            case Lighting::Baked: E = batch_E[batch_next++]; break;
            case Lighting::Full: E = g.irradiance_full(hit); break;
        }
        const Vec3f Le = hit.front ? g.scene_.emission(hit.tri) : Vec3f(0, 0, 0);
        if (hits.irradiance) hits.irradiance[3 * px] = E.x, hits.irradiance[3 * px + 1] = E.y, hits.irradiance[3 * px + 2] = E.z;
        if (slot < 0) {
            const Vec3f L = g.scene_.albedo(hit.tri) * E * kInvPi + Le;
            out[0] = L.x, out[1] = L.y, out[2] = L.z;
            if (hits.uv) hits.uv[2 * px] = hits.uv[2 * px + 1] = kNaN;
            if (hits.lod) hits.lod[px] = kNaN;
            return;
        }
        // The painting coordinates in double from the plane (a 12 m scroll of 150k texels
        // needs more than float), the level from the ray differentials as in the feedback pass.
        const PaintingPlacement& pl = g.placements_[slot];
        const Vec3d dd = dd16[k], n = pl.normal();
        const double t = dot(pl.origin - camera.position, n) / dot(dd, n);
        const Vec3d rel = camera.position + t * dd - pl.origin;
        const double u = std::clamp(dot(rel, pl.u_axis) / pl.width_m, 0.0, 1.0);
        const double v = std::clamp(dot(rel, pl.v_axis) / pl.height_m, 0.0, 1.0);
        double lambda = std::log2(texel_footprint(pl, camera, dd, t));
        if (!std::isfinite(lambda)) lambda = 0;
        uv.push_back(u), uv.push_back(v);
        lods.push_back(float(lambda));
        pending.push_back({x, slot, E * kInvPi, Le});
        if (hits.uv) hits.uv[2 * px] = u, hits.uv[2 * px + 1] = v;
        if (hits.lod) hits.lod[px] = float(lambda);
    }

    // Row y's painting pixels: their texels (one VT call per run of the same painting) and
    // radiance (the exact sRGB curve).
    void paint_row(std::size_t y) {
        float* out_row = rgb + y * std::size_t(camera.width) * 3;
        texels.resize(3 * pending.size());
        for (std::size_t k0 = 0; k0 < pending.size();) {
            std::size_t k1 = k0 + 1;
            while (k1 < pending.size() && pending[k1].slot == pending[k0].slot) ++k1;
            SampleRequest r;
            r.painting = g.placements_[pending[k0].slot].painting;
            r.u = uv.data() + 2 * k0, r.v = r.u + 1, r.uv_stride = 2;
            r.lod = lods.data() + k0;
            r.count = k1 - k0;
            r.filter = Filter::Trilinear;
            r.out = texels.data() + 3 * k0;
            sample_serial(vt, r);
            k0 = k1;
        }
        for (std::size_t k = 0; k < pending.size(); ++k) {
            const Pending& q = pending[k];
            const Vec3f albedo = Vec3f(srgb_to_linear(texels[3 * k] / 255.0f), srgb_to_linear(texels[3 * k + 1] / 255.0f),
                                       srgb_to_linear(texels[3 * k + 2] / 255.0f)) *
                                 kPaintingReflectance;
            const Vec3f L = albedo * q.scale + q.add;
            out_row[3 * q.x] = L.x, out_row[3 * q.x + 1] = L.y, out_row[3 * q.x + 2] = L.z;
        }
    }
};

void Gallery::render_display(const Camera& world_camera, const VirtualTexture& vt, Lighting lighting,
                             float* rgb, const DisplayHits& hits, unsigned threads, bool reference) const {
    require(committed(), "Gallery: commit() before rendering");
    require(rgb != nullptr, "Gallery.render_display: no output");
    check_texture(vt);
    const bool any_hits = hits.position || hits.slot || hits.uv || hits.lod || hits.irradiance;
    if (lighting == Lighting::Baked && !reference && !any_hits) {
        // Before this function's own read lock: GalleryLighting takes it (a second shared
        // lock on the same thread could wait behind a queued light() forever).
        const GalleryLighting light(*this, lighting);
        DisplayPass pass;
        pass.render(feedback_view(), light, vt, world_camera, GalleryLighting::options(threads), rgb);
        return;
    }
    std::shared_lock lock(mutex_);
    if (lighting != Lighting::Unlit) require_lit();
    require(lighting != Lighting::Baked || !bake_offset_.empty(), "Gallery: call bake() before lighting 'baked'");
    const Camera camera = world_camera.moved(-origin_);  // into the room's coordinates
    parallel_for(camera.height, 4, [&](std::size_t row_begin, std::size_t row_end) {
        DisplayOracle oracle(*this, camera, vt, lighting, rgb, hits);
        for (std::size_t y = row_begin; y < row_end; ++y) oracle.row(y);
    }, threads ? threads : lighting_.threads);
}

}  // namespace gigascroll
