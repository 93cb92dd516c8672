#include "views/feedback.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <vector>

#include "common/divider.h"
#include "common/error.h"
#include "common/limits.h"
#include "common/parallel.h"
#include "pack/tile_key.h"

namespace gigascroll {

double texel_footprint(const PaintingPlacement& p, const Camera& camera, Vec3d direction,
                       double t) {
    // dP/dx = t dD/dx - (t dD/dx . n) / (D . n) D: the pixel-step of the hit point along
    // the plane (pinhole camera: the origin does not move between pixels).
    const Vec3d n = p.normal();
    const double dn = dot(direction, n);
    auto transfer = [&](Vec3d dd) {
        const Vec3d dp = t * dd;
        return dp - (dot(dp, n) / dn) * direction;
    };
    auto texels = [&](Vec3d dp) {
        const double du = dot(dp, p.u_axis) * (p.tiles.width() / p.width_m);
        const double dv = dot(dp, p.v_axis) * (p.tiles.height() / p.height_m);
        return std::sqrt(du * du + dv * dv);
    };
    return std::max(texels(transfer(camera.ddx())), texels(transfer(camera.ddy())));
}

double texel_footprint_at_pixel(const PaintingPlacement& p, const Camera& camera, double px,
                                double py) {
    const Vec3d d = camera.direction(px, py);
    const double t = dot(p.origin - camera.position, p.normal()) / dot(d, p.normal());
    return texel_footprint(p, camera, d, t);
}

std::uint32_t mip_level(double lambda, std::uint32_t levels) {
    if (!(lambda > 0)) return 0;  // magnification (and NaN) read level 0
    const double top = static_cast<double>(levels - 1);
    return static_cast<std::uint32_t>(std::min(std::floor(lambda), top));
}

std::uint32_t feedback_width(const Camera& camera, const FeedbackOptions& options) {
    return options.width ? options.width : std::max(1u, camera.width / 8);
}
std::uint32_t feedback_height(const Camera& camera, const FeedbackOptions& options) {
    return options.height ? options.height : std::max(1u, camera.height / 8);
}

FeedbackOptions checked_feedback_options(std::int64_t width, std::int64_t height, double lod_bias,
                                         unsigned threads, std::int64_t display_step) {
    require(width >= 0 && height >= 0 && width < (1 << 16) && height < (1 << 16),
            "view resolution out of range");
    require(display_step >= 1 && display_step < (1 << 16), "display_step must be >= 1");
    return FeedbackOptions{std::uint32_t(width), std::uint32_t(height), lod_bias, threads,
                           std::uint32_t(display_step)};
}

FeedbackShape feedback_shape(const Camera& camera, const FeedbackOptions& options) {
    const std::uint32_t w = feedback_width(camera, options), h = feedback_height(camera, options);
    require_feedback_size(w, h);
    return {w, h, display_extent(w, options.display_step), display_extent(h, options.display_step)};
}

namespace {

// A painting plane seen through a pinhole camera. With the ray direction
// d = F + sx R + sy U (views/camera.h), the hit's texel position is a ratio of linear forms in the
// screen factors (sx, sy):
//   x0 = su (u . (C - O) + N (u . d) / (n . d)),  N = (O - C) . n,  t = N / (n . d),
// and its derivative per display pixel, kx = dsx/dpx, is the Igehy ray differential
// texel_footprint() transfers to the plane, in closed form:
//   dx0/dpx = su kx t (u . R - (u . d) / (n . d) n . R),
// likewise for y0 and dpy. One division per pixel, no square root: the level compares
// rho^2 (see plane_keys). texel_footprint() stays the reference the tests compare against.
struct PlaneFrame {
    PlaneFrame(const PaintingPlacement& p, const Camera& c) {
        const Vec3d n = p.normal(), rel = c.position - p.origin;
        nF = dot(n, c.forward), nR = dot(n, c.right), nU = dot(n, c.up);
        uF = dot(p.u_axis, c.forward), uR = dot(p.u_axis, c.right), uU = dot(p.u_axis, c.up);
        vF = dot(p.v_axis, c.forward), vR = dot(p.v_axis, c.right), vU = dot(p.v_axis, c.up);
        N = -dot(rel, n);
        su = p.tiles.width() / p.width_m, sv = p.tiles.height() / p.height_m;
        uc = dot(rel, p.u_axis), vc = dot(rel, p.v_axis);
        kx2 = std::pow(2 * c.tan_half_x / c.width, 2), ky2 = std::pow(2 * c.tan_half_y / c.height, 2);
        texels_x = p.tiles.width(), texels_y = p.tiles.height();
        inv_width = 1.0 / texels_x, inv_height = 1.0 / texels_y;
        payload = Divider(p.tiles.payload()), levels = p.tiles.levels(), painting = p.painting;
        // tile_key relies on the pyramid's geometry: ceil(ceil(W / 2^l) / P) tiles a row.
        for (std::uint32_t l = 0; l < levels; ++l)
            require(payload(last_texel(texels_x, l)) == p.tiles.tiles_x(l) - 1 &&
                        payload(last_texel(texels_y, l)) == p.tiles.tiles_y(l) - 1,
                    "feedback: the painting's tile grid is not the pack geometry's");
    }
    // The last texel of an axis of n level-0 texels at level l (ceil(n / 2^l) of them).
    static std::uint32_t last_texel(std::uint32_t n, std::uint32_t l) {
        return ((n + (1u << l) - 1) >> l) - 1;
    }

    // The request for level-0 texel position (x, y), clamped to the painting, at `level`.
    // The texel is clamped to the level (x = W at the right edge) before the division, which
    // makes the clamp to the last tile arithmetic (a per-level table would be a gather, the
    // slowest instruction of plane_keys' vectorised loop), and the division is by_double.
    std::uint64_t tile_key(double x, double y, std::uint32_t level) const {
        auto umin = [](std::uint32_t a, std::uint32_t b) { return b < a ? b : a; };
        const std::uint32_t tx = payload.by_double(umin(std::uint32_t(x) >> level, last_texel(texels_x, level)));
        const std::uint32_t ty = payload.by_double(umin(std::uint32_t(y) >> level, last_texel(texels_y, level)));
        return (std::uint64_t(painting) << 37) | (std::uint64_t(level) << 32) | morton2(tx, ty);
    }

    double nF, nR, nU, uF, uR, uU, vF, vR, vU, N, su, sv, uc, vc, kx2, ky2;
    double inv_width, inv_height;
    Divider payload;
    std::uint32_t levels, painting, texels_x, texels_y;
};

// 0.5 log2(x) + bias for n values, branch-free so it vectorises (libm's log2 per pixel was
// a sixth of the pass): exponent e plus log2 of the mantissa m in [1, 2) by the atanh
// series in t = (m - 1) / (m + 1) < 1/3, to t^13 (truncation error < 2e-8). Valid for
// positive normal finite x; the caller redoes the others with std::log2.
void half_log2_run(const double* x, std::size_t n, double bias, double* out) {
    constexpr double c = 2.8853900817779268;  // 2 / ln 2
    constexpr double two52 = 4503599627370496.0;
    for (std::size_t k = 0; k < n; ++k) {
        const std::uint64_t bits = std::bit_cast<std::uint64_t>(x[k]);
        const double m =
            std::bit_cast<double>((bits & 0x000fffffffffffffull) | 0x3ff0000000000000ull);
        // The exponent as a double without an int64 conversion (SSE2 has none).
        const double e =
            std::bit_cast<double>((bits >> 52) | 0x4330000000000000ull) - two52 - 1023;
        const double t = (m - 1) / (m + 1), t2 = t * t;
        const double series =
            1 + t2 * (1.0 / 3 + t2 * (1.0 / 5 + t2 * (1.0 / 7 + t2 * (1.0 / 9 +
                t2 * (1.0 / 11 + t2 * (1.0 / 13))))));
        out[k] = 0.5 * (e + c * t * series) + bias;
    }
}
inline bool normal_positive(double x) {  // & rather than &&: no branch, so loops vectorise
    return (x >= std::numeric_limits<double>::min()) & (x <= std::numeric_limits<double>::max());
}

// The plane's closed form for n pixels of a row (screen factors sx[0..n), row factor s_y):
// rho^2 (the squared footprint in level-0 texels), the texel position clamped to the
// painting, and the request key. The level is exact without a logarithm: the binary
// exponent e of rho^2 satisfies e <= log2(rho^2) < e + 1, so the truncated level
// floor(log2(rho^2) / 2) = floor(e / 2), clamped to the pyramid. Branch-free and on
// restrict pointers so that GCC vectorises all of it, keys included (the key loop that
// reused the last tile's key while pixels stayed in it was a third of the pass).
void plane_keys(const PlaneFrame& f, const double* __restrict sx, double s_y, std::size_t n,
                double* __restrict rho2, double* __restrict x0, double* __restrict y0,
                std::uint64_t* __restrict keys) {
    // Constants in locals and min/max by value: GCC then if-converts and vectorises.
    auto max = [](double a, double b) { return a < b ? b : a; };
    auto min = [](double a, double b) { return b < a ? b : a; };
    auto umin = [](std::uint32_t a, std::uint32_t b) { return b < a ? b : a; };
    const PlaneFrame frame = f;  // a local copy, so no store in the loop can alias it
    const double Dr = f.nF + s_y * f.nU, Ar = f.uF + s_y * f.uU, Br = f.vF + s_y * f.vU;
    const double nR = f.nR, uR = f.uR, vR = f.vR, nU = f.nU, uU = f.uU, vU = f.vU, N = f.N;
    const double su = f.su, sv = f.sv, kx2 = f.kx2, ky2 = f.ky2, xc = f.su * f.uc,
                 yc = f.sv * f.vc, sN = f.su * f.N, vN = f.sv * f.N, W = f.texels_x,
                 H = f.texels_y;
    const std::uint32_t top = f.levels - 1;
    for (std::size_t k = 0; k < n; ++k) {
        const double inv = 1.0 / (Dr + sx[k] * nR);
        const double a = (Ar + sx[k] * uR) * inv, b = (Br + sx[k] * vR) * inv;
        const double t = N * inv;
        const double ex = su * (uR - a * nR), fx = sv * (vR - b * nR);
        const double ey = su * (uU - a * nU), fy = sv * (vU - b * nU);
        const double r2 = t * t * max(kx2 * (ex * ex + fx * fx), ky2 * (ey * ey + fy * fy));
        const double x = min(max(xc + sN * a, 0.0), W), y = min(max(yc + vN * b, 0.0), H);
        rho2[k] = r2, x0[k] = x, y0[k] = y;
        // rho^2 <= 1 (magnification) and NaN read level 0.
        const auto e = std::uint32_t(std::bit_cast<std::uint64_t>(r2) >> 52) - 1023u;
        const std::uint32_t level = r2 > 1.0 ? umin(e >> 1, top) : 0u;
        keys[k] = frame.tile_key(x, y, level);
    }
}

}  // namespace

void render_view(const ExhibitionScene& scene, const Camera& camera,
                     const FeedbackOptions& options, std::uint64_t* keys, float* lod,
                     double* uv) {
    require(scene.committed(), "commit() the exhibition scene before the feedback pass");
    render_view(scene.view(), camera, options, keys, lod, uv);
}

void render_view(const PaintingSceneView& scene, const Camera& world_camera,
                 const FeedbackOptions& options, std::uint64_t* keys, float* lod, double* uv) {
    require(scene.handle != nullptr, "render_view: the scene has no BVH");
    const Camera camera = world_camera.moved(-scene.origin);  // into the BVH's coordinates
    require(std::isfinite(options.lod_bias), "lod_bias must be finite");
    const std::uint32_t fw = feedback_width(camera, options), fh = feedback_height(camera, options);
    require(fw <= camera.width && fh <= camera.height,
            "feedback resolution must not exceed the display resolution");
    const double sx = double(camera.width) / fw, sy = double(camera.height) / fh;
    const RTCScene handle = scene.handle;
    const bool biased = options.lod_bias != 0;
    require(options.display_step >= 1, "display_step must be >= 1");
    const std::uint32_t ds = options.display_step, dw = (fw + ds - 1) / ds;

    // Per-pass constants: each column's and row's screen factor, each painting's plane.
    // Columns padded to whole 16-ray packets with the last column's factor.
    const std::size_t padded = (fw + 15) / 16 * 16;
    std::vector<double> column_sx(padded), row_sy(fh);
    for (std::uint32_t i = 0; i < fw; ++i) column_sx[i] = camera.screen_x((i + 0.5) * sx);
    std::fill(column_sx.begin() + fw, column_sx.end(), column_sx[fw - 1]);
    for (std::uint32_t j = 0; j < fh; ++j) row_sy[j] = camera.screen_y((j + 0.5) * sy);
    std::vector<PlaneFrame> planes;
    planes.reserve(scene.paintings.size());
    for (const auto& p : scene.paintings) planes.emplace_back(p, camera);
    const float org_x = float(camera.position.x), org_y = float(camera.position.y),
                org_z = float(camera.position.z);
    constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
    // A near plane of a few float ulps of the position (at least 10 um): a camera standing on
    // a corner of a box or painting sees past it instead of hitting it at t ~ 0.
    const float near = std::max(1e-5f, 4e-7f * std::max({std::abs(org_x), std::abs(org_y), std::abs(org_z)}));

    parallel_for(fh, 4, [&](std::size_t row_begin, std::size_t row_end) {
        // The fields Embree only reads and that no pixel changes are set once per thread;
        // per packet only the directions, tfar and the hit's geometry id.
        RTCRayHit16 packet;
        for (std::uint32_t k = 0; k < 16; ++k) {
            packet.ray.org_x[k] = org_x, packet.ray.org_y[k] = org_y;
            packet.ray.org_z[k] = org_z;
            packet.ray.tnear[k] = near;
            packet.ray.time[k] = 0.f;
            packet.ray.mask[k] = ~0u;
            packet.ray.id[k] = k;
            packet.ray.flags[k] = 0;
            packet.hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
        }
        // A row's runs of pixels that see the same painting (or none: placement -1).
        struct Run {
            std::uint32_t begin, end;
            int placement;
        };
        std::vector<Run> runs;
        std::vector<double> rho2(fw), x0(fw), y0(fw), lambda(fw);
        // The row's ray directions as Embree takes them, for whole packets (a vectorised
        // loop here; per packet only copies).
        std::vector<float> dir_x(padded), dir_y(padded), dir_z(padded);
        for (std::size_t row = row_begin; row < row_end; ++row) {
            const double s_y = row_sy[row];
            const Vec3d row_dir = camera.forward + s_y * camera.up;
            const Vec3d right = camera.right;
            for (std::size_t i = 0; i < padded; ++i) {
                const double c = column_sx[i];
                dir_x[i] = float(row_dir.x + c * right.x);
                dir_y[i] = float(row_dir.y + c * right.y);
                dir_z[i] = float(row_dir.z + c * right.z);
            }
            runs.clear();
            auto extend = [&](std::uint32_t begin, std::uint32_t end, int pl) {
                if (!runs.empty() && runs.back().placement == pl) runs.back().end = end;
                else runs.push_back({begin, end, pl});
            };
            // Visibility: Embree packets of 16 consecutive pixels of the row.
            for (std::uint32_t i0 = 0; i0 < fw; i0 += 16) {
                const std::uint32_t n = std::min<std::uint32_t>(16, fw - i0);
                alignas(64) int valid[16];
                std::memcpy(packet.ray.dir_x, dir_x.data() + i0, sizeof packet.ray.dir_x);
                std::memcpy(packet.ray.dir_y, dir_y.data() + i0, sizeof packet.ray.dir_y);
                std::memcpy(packet.ray.dir_z, dir_z.data() + i0, sizeof packet.ray.dir_z);
                for (std::uint32_t k = 0; k < 16; ++k) {
                    valid[k] = k < n ? -1 : 0;
                    packet.ray.tfar[k] = std::numeric_limits<float>::infinity();
                    packet.hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
                }
                RTCIntersectContext context;
                rtcInitIntersectContext(&context);
                context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
                rtcIntersect16(valid, handle, &context, &packet);
                // Mostly the whole packet sees one surface: one run step for all of it.
                const unsigned g0 = packet.hit.geomID[0];
                bool uniform = true;
                for (std::uint32_t k = 1; k < n; ++k) uniform &= packet.hit.geomID[k] == g0;
                auto placement = [&](unsigned g) {
                    return g == RTC_INVALID_GEOMETRY_ID ? -1 : scene.placement_of(g);
                };
                if (uniform) {
                    extend(i0, i0 + n, placement(g0));
                } else {
                    for (std::uint32_t k = 0; k < n; ++k)
                        extend(i0 + k, i0 + k + 1, placement(packet.hit.geomID[k]));
                }
            }

            // Shading, run by run: the plane's closed form and the keys (plane_keys), then
            // lod and uv where the display grid needs them.
            std::uint64_t* out = keys + row * fw;
            // lod and uv only on the display grid: every ds-th pixel of every ds-th row,
            // stored at (row / ds, column / ds).
            const bool display_row = row % ds == 0;
            float* out_lod = lod && display_row ? lod + (row / ds) * dw : nullptr;
            double* out_uv = uv && display_row ? uv + 2 * (row / ds) * dw : nullptr;
            for (const Run& run : runs) {
                const std::uint32_t i0 = run.begin, i1 = run.end, n = i1 - i0;
                // The run's display columns are c = d * ds for d in [d0, d1).
                const std::uint32_t d0 = (i0 + ds - 1) / ds, d1 = (i1 + ds - 1) / ds;
                if (run.placement < 0) {
                    std::fill(out + i0, out + i1, kNoRequest);
                    if (out_lod) std::fill(out_lod + d0, out_lod + d1, kNaN);
                    if (out_uv) std::fill(out_uv + 2 * d0, out_uv + 2 * d1, double(kNaN));
                    continue;
                }
                const PlaneFrame& f = planes[run.placement];
                plane_keys(f, column_sx.data() + i0, s_y, n, rho2.data(), x0.data(), y0.data(),
                           out + i0);
                if (out_lod || biased) {  // out_lod is null off the display grid
                    half_log2_run(rho2.data(), n, options.lod_bias, lambda.data());
                    std::uint32_t outside = 0;  // counted first: this loop vectorises
                    for (std::uint32_t k = 0; k < n; ++k) outside += !normal_positive(rho2[k]);
                    for (std::uint32_t k = 0; outside && k < n; ++k)
                        if (!normal_positive(rho2[k]))
                            lambda[k] = 0.5 * std::log2(rho2[k]) + options.lod_bias;
                    if (out_lod)
                        for (std::uint32_t d = d0; d < d1; ++d)
                            out_lod[d] = float(lambda[d * ds - i0]);
                }
                if (biased) {  // the level from lambda + bias instead (tests; Vulkan-SVT's bias)
                    for (std::uint32_t k = 0; k < n; ++k)
                        out[i0 + k] = f.tile_key(x0[k], y0[k], mip_level(lambda[k], f.levels));
                }
                if (out_uv) {
                    for (std::uint32_t d = d0; d < d1; ++d) {
                        out_uv[2 * d] = x0[d * ds - i0] * f.inv_width;
                        out_uv[2 * d + 1] = y0[d * ds - i0] * f.inv_height;
                    }
                }
            }
        }
    }, options.threads);
}

void require_feedback_size(std::uint64_t width, std::uint64_t height) {
    const double pixels = double(width) * double(height);
    if (pixels <= double(kMaxFeedbackPixels)) return;
    throw InvalidArgument("render_view: a " + std::to_string(width) + " x " + std::to_string(height) +
                          " feedback pass would need " + format_bytes(pixels * 28) +
                          "; at most 2^26 pixels (8192 x 8192)");
}

}  // namespace gigascroll
