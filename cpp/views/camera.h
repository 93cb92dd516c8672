// The one pinhole camera of the core: an eye of the headset, the magnifier, or the camera of
// a photon-mapped render. Right-handed frame: `forward` into the scene, `up`, and
// right = forward x up; display pixel (0, 0) is the top-left corner, pixel centres at +0.5,
// y down. The field of view is given by the tangents of its half angles (symmetric frustum);
// look_at() builds the same camera from a target and a vertical field of view in degrees,
// with square pixels.
#pragma once
#include <cstdint>

#include "common/vec3.h"

namespace gigascroll {

struct Camera {
    // `forward` and `up` need not be unit or orthogonal: the constructor orthonormalises them.
    // width x height: the display resolution (the mip level is chosen for it).
    Camera(Vec3d position, Vec3d forward, Vec3d up, double tan_half_x, double tan_half_y,
           std::uint32_t width, std::uint32_t height);
    // Looking from `position` at `target`; fov_y_deg in (0, 180); tan_half_x follows from the
    // aspect ratio.
    static Camera look_at(Vec3d position, Vec3d target, Vec3d up, double fov_y_deg,
                          std::uint32_t width, std::uint32_t height);

    Vec3d position, forward, up, right;
    double tan_half_x, tan_half_y;
    std::uint32_t width, height;

    // Unnormalised direction through display coordinates (px, py). Its derivatives per
    // display pixel are right * dx_scale and -up * dy_scale.
    Vec3d direction(double px, double py) const {
        return direction_at(screen_x(px), screen_y(py));
    }
    // The two factors of direction(), separable so a pass over a pixel grid computes each
    // column's and row's once (same arithmetic, so the same bits).
    double screen_x(double px) const { return (2 * px / width - 1) * tan_half_x; }
    double screen_y(double py) const { return (1 - 2 * py / height) * tan_half_y; }
    Vec3d direction_at(double sx, double sy) const { return forward + sx * right + sy * up; }
    Vec3d ddx() const { return (2 * tan_half_x / width) * right; }
    Vec3d ddy() const { return (-2 * tan_half_y / height) * up; }

    // Single-precision rays for the photon renderer (Embree's precision): the origin and the
    // unit direction through film position (px, py).
    Vec3f ray_origin() const { return Vec3f(position); }
    Vec3f ray_direction(float px, float py) const;
    // VR-photon-mapping eqs. (3)-(5): r_dir = M_rotate (p - eye), r_clip = M_proj r_dir,
    // index = floor((r_clip + 1) / 2 * size). False when p is behind the eye or off the film.
    bool project(Vec3f p, int& px, int& py) const;
    // Vertical field of view in degrees.
    double fov_y_degrees() const;
    // The same camera translated by offset.
    Camera moved(Vec3d offset) const;
};

// Two parallel eyes ipd apart along the centre camera's right vector (VR-photon-mapping §3.3, and
// the headset's eyes).
struct StereoCamera {
    StereoCamera(const Camera& centre, double ipd);
    Camera left, right;
    double ipd;
};

}  // namespace gigascroll
