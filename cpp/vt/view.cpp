#include "vt/view.h"

#include <cmath>

#include "common/error.h"

namespace gigascroll {

Camera::Camera(Vec3 position_, Vec3 forward_, Vec3 up_, double tan_half_x_, double tan_half_y_,
               std::uint32_t width_, std::uint32_t height_)
    : position(position_), tan_half_x(tan_half_x_), tan_half_y(tan_half_y_), width(width_),
      height(height_) {
    require(is_finite(position_) && is_finite(forward_) && is_finite(up_),
            "camera position and orientation must be finite (no NaN)");
    require(std::isfinite(tan_half_x_) && std::isfinite(tan_half_y_) && tan_half_x_ > 0 &&
                tan_half_y_ > 0,
            "camera field of view must be in (0, 180) degrees");
    require(width_ > 0 && height_ > 0, "camera resolution must be positive");
    require(length(forward_) > 0, "camera forward vector is zero");
    forward = normalize(forward_);
    const Vec3 r = cross(forward, up_);
    require(length(r) > 1e-9 * length(up_) && length(up_) > 0,
            "camera up vector is zero or parallel to forward");
    right = normalize(r);
    up = cross(right, forward);
}

}  // namespace gigascroll
