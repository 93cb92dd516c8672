#include "vt/feedback.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "common/error.h"
#include "common/parallel.h"
#include "vt/request.h"

namespace gigascroll {

namespace {
// What texel_footprint needs of a painting and a camera, computed once per pass instead of
// once per pixel (the per-pixel arithmetic below is unchanged, so the result is too).
struct FootprintFrame {
    FootprintFrame(const PaintingPlacement& p, const Camera& camera)
        : n(p.normal()), ddx(camera.ddx()), ddy(camera.ddy()), u_axis(p.u_axis),
          v_axis(p.v_axis), su(p.tiles.width() / p.width_m), sv(p.tiles.height() / p.height_m) {}
    Vec3 n, ddx, ddy, u_axis, v_axis;
    double su, sv;

    double operator()(Vec3 direction, double t) const {
        // dP/dx = t dD/dx - (t dD/dx . n) / (D . n) D: the pixel-step of the hit point along
        // the plane (pinhole camera: the origin does not move between pixels).
        const double dn = dot(direction, n);
        auto transfer = [&](Vec3 dd) {
            const Vec3 dp = t * dd;
            return dp - (dot(dp, n) / dn) * direction;
        };
        const Vec3 dpx = transfer(ddx), dpy = transfer(ddy);
        auto texels = [&](Vec3 dp) {
            const double du = dot(dp, u_axis) * su, dv = dot(dp, v_axis) * sv;
            return std::sqrt(du * du + dv * dv);
        };
        return std::max(texels(dpx), texels(dpy));
    }
};
}  // namespace

double texel_footprint(const PaintingPlacement& painting, const Camera& camera, Vec3 direction,
                       double t) {
    return FootprintFrame(painting, camera)(direction, t);
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

void render_feedback(const ExhibitionScene& scene, const Camera& camera,
                     const FeedbackOptions& options, std::uint64_t* keys, float* lod,
                     double* uv) {
    require(scene.committed(), "commit() the exhibition scene before the feedback pass");
    require(std::isfinite(options.lod_bias), "lod_bias must be finite");
    const std::uint32_t fw = feedback_width(camera, options), fh = feedback_height(camera, options);
    require(fw <= camera.width && fh <= camera.height,
            "feedback resolution must not exceed the display resolution");
    const double sx = double(camera.width) / fw, sy = double(camera.height) / fh;
    const RTCScene handle = scene.handle();
    const auto& paintings = scene.paintings();

    // Per-pass constants: each column's and row's screen factor, each painting's footprint
    // frame (profiling showed the per-pixel shading, not Embree, dominating the pass).
    std::vector<double> column_sx(fw), row_sy(fh);
    for (std::uint32_t i = 0; i < fw; ++i) column_sx[i] = camera.screen_x((i + 0.5) * sx);
    for (std::uint32_t j = 0; j < fh; ++j) row_sy[j] = camera.screen_y((j + 0.5) * sy);
    std::vector<FootprintFrame> frames;
    frames.reserve(paintings.size());
    for (const auto& p : paintings) frames.emplace_back(p, camera);

    parallel_for(fh, 4, [&](std::size_t row_begin, std::size_t row_end) {
        std::vector<RTCRayHit> rays(fw);
        std::vector<Vec3> dirs(fw);
        for (std::size_t row = row_begin; row < row_end; ++row) {
            for (std::uint32_t i = 0; i < fw; ++i) {
                // The feedback pixel's centre, in display pixel coordinates.
                const Vec3 d = camera.direction_at(column_sx[i], row_sy[row]);
                dirs[i] = d;
                RTCRayHit& r = rays[i];
                r.ray.org_x = float(camera.position.x);
                r.ray.org_y = float(camera.position.y);
                r.ray.org_z = float(camera.position.z);
                r.ray.dir_x = float(d.x);
                r.ray.dir_y = float(d.y);
                r.ray.dir_z = float(d.z);
                r.ray.tnear = 0.f;
                r.ray.tfar = std::numeric_limits<float>::infinity();
                r.ray.time = 0.f;
                r.ray.mask = ~0u;
                r.ray.id = i;
                r.ray.flags = 0;
                r.hit.geomID = RTC_INVALID_GEOMETRY_ID;
                r.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
            }
            RTCIntersectContext context;
            rtcInitIntersectContext(&context);
            context.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
            rtcIntersect1M(handle, &context, rays.data(), fw, sizeof(RTCRayHit));

            std::uint64_t* out = keys + row * fw;
            float* out_lod = lod ? lod + row * fw : nullptr;
            double* out_uv = uv ? uv + 2 * row * fw : nullptr;
            for (std::uint32_t i = 0; i < fw; ++i) {
                const RTCRayHit& r = rays[i];
                const int placement = r.hit.geomID == RTC_INVALID_GEOMETRY_ID
                                          ? -1
                                          : scene.placement_of(r.hit.geomID);
                if (placement < 0) {
                    out[i] = kNoRequest;
                    if (out_lod) out_lod[i] = std::numeric_limits<float>::quiet_NaN();
                    if (out_uv)
                        out_uv[2 * i] = out_uv[2 * i + 1] = std::numeric_limits<double>::quiet_NaN();
                    continue;
                }
                const PaintingPlacement& p = paintings[placement];
                const Vec3 d = dirs[i];
                // Re-intersect the plane in double: the float t is too coarse for texel
                // positions on a 12 m scroll.
                const FootprintFrame& frame = frames[placement];
                const Vec3 n = frame.n;
                const double t = dot(p.origin - camera.position, n) / dot(d, n);
                const Vec3 hit = camera.position + t * d - p.origin;
                const double lambda = std::log2(frame(d, t)) + options.lod_bias;
                const std::uint32_t level = mip_level(lambda, p.tiles.levels());
                const double u = std::clamp(dot(hit, p.u_axis) / p.width_m, 0.0, 1.0);
                const double v = std::clamp(dot(hit, p.v_axis) / p.height_m, 0.0, 1.0);
                const double scale = double(p.tiles.payload()) * std::ldexp(1.0, int(level));
                const auto tx = std::min<std::uint32_t>(
                    std::uint32_t(u * p.tiles.width() / scale), p.tiles.tiles_x(level) - 1);
                const auto ty = std::min<std::uint32_t>(
                    std::uint32_t(v * p.tiles.height() / scale), p.tiles.tiles_y(level) - 1);
                out[i] = pack_request(p.painting, level, tx, ty);
                if (out_lod) out_lod[i] = float(lambda);
                if (out_uv) out_uv[2 * i] = u, out_uv[2 * i + 1] = v;
            }
        }
    }, options.threads);
}

}  // namespace gigascroll
