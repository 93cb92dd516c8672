// A pinhole view: an eye of the headset or the magnifier camera.
#pragma once
#include <cstdint>

#include "vt/vec3.h"

namespace gigascroll {

struct Camera {
    // `forward` and `up` need not be unit or orthogonal: the constructor orthonormalises them.
    // tan_half_x / tan_half_y: tangents of the half field of view (symmetric frustum).
    // width x height: the display resolution the mip level is chosen for.
    Camera(Vec3 position, Vec3 forward, Vec3 up, double tan_half_x, double tan_half_y,
           std::uint32_t width, std::uint32_t height);

    Vec3 position, forward, up, right;
    double tan_half_x, tan_half_y;
    std::uint32_t width, height;

    // Unnormalised direction through display coordinates (px, py), pixel centres at +0.5,
    // y down. Its derivatives per display pixel are right * dx_scale and -up * dy_scale.
    Vec3 direction(double px, double py) const {
        return direction_at(screen_x(px), screen_y(py));
    }
    // The two factors of direction(), separable so a pass over a pixel grid computes each
    // column's and row's once (same arithmetic, so the same bits).
    double screen_x(double px) const { return (2 * px / width - 1) * tan_half_x; }
    double screen_y(double py) const { return (1 - 2 * py / height) * tan_half_y; }
    Vec3 direction_at(double sx, double sy) const { return forward + sx * right + sy * up; }
    Vec3 ddx() const { return (2 * tan_half_x / width) * right; }
    Vec3 ddy() const { return (-2 * tan_half_y / height) * up; }
};

}  // namespace gigascroll
