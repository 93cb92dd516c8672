#include "photon/camera.h"

#include <cmath>

#include "common/error.h"

namespace gigascroll::photon {

Camera::Camera(Vec3 position, Vec3 look_at, Vec3 up, float fov_deg, int width, int height)
    : pos_(position), fov_(fov_deg), w_(width), h_(height) {
    require(finite(position) && finite(look_at) && finite(up), "Camera: position, look_at and up must be finite");
    require(std::isfinite(fov_deg) && fov_deg > 0.0f && fov_deg < 180.0f, "Camera: fov must be in (0, 180) degrees");
    require(width > 0 && height > 0 && width <= 65536 && height <= 65536,
            "Camera: resolution must be positive (at most 65536 per side)");
    const Vec3 f = look_at - position;
    require(length(f) > 0.0f, "Camera: look_at equals position");
    fwd_ = normalize(f);
    const Vec3 r = cross(fwd_, up);
    require(length(r) > 1e-6f * length(up), "Camera: up is parallel to the viewing direction");
    right_ = normalize(r);
    up_ = cross(right_, fwd_);
    tan_half_ = std::tan(0.5f * fov_deg * float(M_PI) / 180.0f);
    aspect_ = float(width) / float(height);
}

Vec3 Camera::direction(float px, float py) const {
    const float sx = (2.0f * px / float(w_) - 1.0f) * tan_half_ * aspect_;
    const float sy = (1.0f - 2.0f * py / float(h_)) * tan_half_;
    return normalize(fwd_ + right_ * sx + up_ * sy);
}

bool Camera::project(Vec3 p, int& px, int& py) const {
    const Vec3 d = p - pos_;
    const Vec3 dir{dot(d, right_), dot(d, up_), dot(d, fwd_)};  // M_rotate
    if (!(dir.z > 0.0f)) return false;
    const float cx = dir.x / (dir.z * tan_half_ * aspect_);     // M_proj, then divide by w
    const float cy = dir.y / (dir.z * tan_half_);
    const float fx = std::floor((cx + 1.0f) * 0.5f * float(w_));
    const float fy = std::floor((1.0f - cy) * 0.5f * float(h_));  // rows grow downward
    if (!(fx >= 0.0f && fx < float(w_) && fy >= 0.0f && fy < float(h_))) return false;
    px = int(fx);
    py = int(fy);
    return true;
}

Camera Camera::moved(Vec3 offset) const {
    Camera c = *this;
    c.pos_ = pos_ + offset;
    return c;
}

StereoCamera::StereoCamera(const Camera& center, float ipd_)
    : left(center.moved(center.right() * (-0.5f * ipd_))),
      right(center.moved(center.right() * (0.5f * ipd_))),
      ipd(ipd_) {
    require(std::isfinite(ipd_) && ipd_ >= 0.0f, "StereoCamera: ipd must be finite and non-negative");
}

}  // namespace gigascroll::photon
