// Pinhole cameras: one view, and a stereo pair of parallel eyes for stereo reuse.
#pragma once
#include "photon/vec.h"

namespace gigascroll::photon {

class Camera {
public:
    // fov_deg: vertical field of view in degrees; pixel (0, 0) is the top-left corner.
    Camera(Vec3 position, Vec3 look_at, Vec3 up, float fov_deg, int width, int height);

    // Direction of the ray through film position (px, py), both in pixels.
    Vec3 direction(float px, float py) const;
    // Seed 001 eqs. (3)-(5): r_dir = M_rotate (r_hit - r_eye), r_clip = M_proj r_dir,
    // index = floor((r_clip + 1) / 2 * size). False when p is behind the eye or off the film.
    bool project(Vec3 p, int& px, int& py) const;

    Vec3 position() const { return pos_; }
    Vec3 forward() const { return fwd_; }
    Vec3 right() const { return right_; }
    Vec3 up() const { return up_; }
    float fov() const { return fov_; }
    int width() const { return w_; }
    int height() const { return h_; }
    Camera moved(Vec3 offset) const;  // the same camera translated by offset

private:
    Vec3 pos_, fwd_, right_, up_;
    float fov_, tan_half_, aspect_;
    int w_, h_;
};

// Two parallel eyes separated by ipd along the camera's right vector.
struct StereoCamera {
    StereoCamera(const Camera& center, float ipd);
    Camera left, right;
    float ipd;
};

}  // namespace gigascroll::photon
