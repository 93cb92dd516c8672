#include "views/camera.h"

#include <cmath>

#include "common/error.h"
#include "common/limits.h"

namespace gigascroll {

Camera::Camera(Vec3d position_, Vec3d forward_, Vec3d up_, double tan_half_x_, double tan_half_y_,
               std::uint32_t width_, std::uint32_t height_)
    : position(position_), tan_half_x(tan_half_x_), tan_half_y(tan_half_y_), width(width_),
      height(height_) {
    // Every ray of the core starts at a camera or in a bounded scene: bounding the position
    // here keeps Embree's ray check (an abort) out of reach.
    require_coordinate(position_, "camera position");
    require(is_finite(forward_) && is_finite(up_), "camera forward and up vectors must be finite (no NaN or Inf)");
    require(std::isfinite(tan_half_x_) && std::isfinite(tan_half_y_) && tan_half_x_ > 0 &&
                tan_half_y_ > 0 && tan_half_x_ <= kMaxTanHalfFov && tan_half_y_ <= kMaxTanHalfFov,
            "camera field of view must be in (0, 180) degrees (tan_half_x and tan_half_y in (0, 1e6])");
    require(width_ > 0 && height_ > 0, "camera resolution must be positive");
    require(max_component(vabs(forward_)) > 0, "camera forward vector is zero");
    require(max_component(vabs(up_)) > 0, "camera up vector is zero");
    // Vectors whose squared length overflows or underflows are rescaled first; the others
    // are used as given (the same bits as always).
    const auto tame = [](Vec3d v) {
        const double l = length(v);
        return std::isfinite(l) && l > 1e-150 ? v : v / max_component(vabs(v));
    };
    const Vec3d up_tamed = tame(up_);
    forward = normalize(tame(forward_));
    const Vec3d r = cross(forward, up_tamed);
    require(length(r) > 1e-9 * length(up_tamed), "camera up vector is parallel to forward");
    right = normalize(r);
    up = cross(right, forward);
}

Camera Camera::look_at(Vec3d position, Vec3d target, Vec3d up, double fov_y_deg,
                       std::uint32_t width, std::uint32_t height) {
    require_coordinate(position, "camera: position");
    require_coordinate(target, "camera: look_at");
    require(is_finite(up), "camera: up must be finite (no NaN or Inf)");
    require(max_component(vabs(up)) > 0, "camera: up vector is zero");
    require(std::isfinite(fov_y_deg) && fov_y_deg > 0 && fov_y_deg < 180,
            "camera: fov must be in (0, 180) degrees");
    require(width > 0 && height > 0 && width <= 65536 && height <= 65536,
            "camera: resolution must be positive (at most 65536 per side)");
    // The frame and the tangent in single precision, as the photon renderer's cameras have
    // always been set up: a scene's default camera renders the same image as before the views
    // and the renderer shared this type (ray_direction() is single precision anyway).
    // An up vector beyond float's comfortable range is rescaled (others keep their bits).
    const double up_max = max_component(vabs(up));
    const Vec3f p(position), t(target), u(up_max > 1e-18 && up_max < 1e18 ? up : up / up_max);
    require(length(t - p) > 0.0f, "camera: look_at equals position");
    require(length(u) > 0.0f, "camera: up must be a non-zero vector");
    const Vec3f f = normalize(t - p);
    const Vec3f r = cross(f, u);
    require(length(r) > 1e-6f * length(u), "camera: up is parallel to the viewing direction");
    const Vec3f right = normalize(r), true_up = cross(right, f);
    const float tan_half = std::tan(0.5f * float(fov_y_deg) * float(M_PI) / 180.0f);
    const float aspect = float(width) / float(height);
    // tan_half_x exactly tan_half * aspect (a product of two floats is exact in double), so
    // ray_direction() recovers both factors and multiplies them in the old order.
    Camera c(position, Vec3d(f), Vec3d(true_up), double(tan_half) * double(aspect),
             double(tan_half), width, height);
    c.forward = Vec3d(f), c.right = Vec3d(right), c.up = Vec3d(true_up);
    return c;
}

Vec3f Camera::ray_direction(float px, float py) const {
    const float t = float(tan_half_y), aspect = float(tan_half_x / tan_half_y);
    const float sx = (2.0f * px / float(width) - 1.0f) * t * aspect;
    const float sy = (1.0f - 2.0f * py / float(height)) * t;
    return normalize(Vec3f(forward) + Vec3f(right) * sx + Vec3f(up) * sy);
}

bool Camera::project(Vec3f p, int& px, int& py) const {
    const Vec3f d = p - ray_origin();
    const Vec3f dir{dot(d, Vec3f(right)), dot(d, Vec3f(up)), dot(d, Vec3f(forward))};  // M_rotate
    if (!(dir.z > 0.0f)) return false;
    const float t = float(tan_half_y), aspect = float(tan_half_x / tan_half_y);
    const float cx = dir.x / (dir.z * t * aspect);  // M_proj, then divide by w
    const float cy = dir.y / (dir.z * t);
    const float fx = std::floor((cx + 1.0f) * 0.5f * float(width));
    const float fy = std::floor((1.0f - cy) * 0.5f * float(height));  // rows grow downward
    if (!(fx >= 0.0f && fx < float(width) && fy >= 0.0f && fy < float(height))) return false;
    px = int(fx);
    py = int(fy);
    return true;
}

double Camera::fov_y_degrees() const { return 2.0 * std::atan(tan_half_y) * 180.0 / M_PI; }

Camera Camera::moved(Vec3d offset) const {
    Camera c = *this;
    c.position = position + offset;
    require_coordinate(c.position, "camera position");
    return c;
}

namespace {
// Checked before either eye is placed, so no eye is ever out of the coordinate bound.
double checked_ipd(const Camera& centre, double ipd) {
    require(std::isfinite(ipd) && ipd >= 0.0, "StereoCamera: ipd must be finite and non-negative");
    require_coordinate(centre.position + centre.right * (0.5 * ipd),
                       "StereoCamera: the right eye (camera position + ipd / 2 * right)");
    require_coordinate(centre.position - centre.right * (0.5 * ipd),
                       "StereoCamera: the left eye (camera position - ipd / 2 * right)");
    return ipd;
}
}  // namespace

StereoCamera::StereoCamera(const Camera& centre, double ipd_)
    : left(centre.moved(centre.right * (-0.5 * checked_ipd(centre, ipd_)))),
      right(centre.moved(centre.right * (0.5 * ipd_))), ipd(ipd_) {}

}  // namespace gigascroll
