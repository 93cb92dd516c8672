// Camera projection inverts the ray through a pixel.
#include <gtest/gtest.h>

#include "common/vec3.h"
#include "views/camera.h"

using namespace gigascroll;

TEST(Camera, ProjectInvertsTheRayThroughAPixel) {
    const Camera cam = Camera::look_at({0.3, 1.0, 4.0}, {0, 0, 0}, {0, 1, 0}, 45.0, 80, 60);
    for (int y = 0; y < 60; y += 7)
        for (int x = 0; x < 80; x += 9) {
            const Vec3f p = cam.ray_origin() + cam.ray_direction(float(x) + 0.5f, float(y) + 0.5f) * 3.7f;
            int px = -1, py = -1;
            ASSERT_TRUE(cam.project(p, px, py));
            EXPECT_EQ(px, x);
            EXPECT_EQ(py, y);
        }
    int px, py;
    EXPECT_FALSE(cam.project(cam.ray_origin() - Vec3f(cam.forward), px, py));  // behind the eye
}
