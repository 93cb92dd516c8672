// Lambert's polygon formula (photon/polygon_irradiance.h) against Howell's closed form for a
// parallel rectangle and against brute-force quadrature of cos_x cos_l / d^2 over emitters
// that cross the receiver's horizon.
#include <gtest/gtest.h>

#include <cmath>

#include "photon/polygon_irradiance.h"

using namespace gigascroll;

namespace {

// Irradiance at the origin (receiver facing +y) from a rectangle of radiance 1 at height h over
// x in [x0, x1], z in [z0, z1], facing down: the corner form factors (Howell's catalogue,
// differential area to a parallel rectangle) times pi.
double parallel_rectangle(double h, double x0, double x1, double z0, double z1) {
    auto corner = [h](double a, double b) {
        const double X = a / h, Y = b / h, sx = std::sqrt(1 + X * X), sy = std::sqrt(1 + Y * Y);
        return (X / sx * std::atan(Y / sx) + Y / sy * std::atan(X / sy)) / 2;
    };
    return corner(x1, z1) - corner(x0, z1) - corner(x1, z0) + corner(x0, z0);
}

// The integral over the quad (a, b, c, d) (planar, facing ne) of max(0, cos_x) cos_l / d^2 by
// the midpoint rule on an m x m grid, in double.
double quadrature(Vec3f x, Vec3f n, Vec3f a, Vec3f b, Vec3f d, Vec3f ne, int m = 1500) {
    const Vec3d u = Vec3d(b) - Vec3d(a), v = Vec3d(d) - Vec3d(a);
    const double area = length(cross(u, v)) / (double(m) * m);
    double sum = 0;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            const Vec3d p = Vec3d(a) + u * ((i + 0.5) / m) + v * ((j + 0.5) / m);
            const Vec3d w = p - Vec3d(x);
            const double d2 = dot(w, w), cx = dot(Vec3d(n), w), cl = -dot(Vec3d(ne), w);
            if (cx > 0 && cl > 0) sum += cx * cl / (d2 * d2) * area;
        }
    return sum;
}

// A quad's two triangles (a, b, c) and (a, c, d): their diagonal a-c is edge 2 of the first
// and edge 0 of the second.
float quad_irradiance(Vec3f x, Vec3f n, Vec3f a, Vec3f b, Vec3f c, Vec3f d, bool skip_diagonal) {
    return unit_triangle_irradiance(x, n, a, b, c, skip_diagonal ? 4u : 0u) +
           unit_triangle_irradiance(x, n, a, c, d, skip_diagonal ? 1u : 0u);
}

}  // namespace

TEST(PolygonIrradiance, ParallelRectangleMatchesHowellsFormula) {
    const Vec3f n(0, 1, 0);
    for (auto [x0, x1, z0, z1] : {std::array<float, 4>{-0.25f, 0.25f, -0.25f, 0.25f}, {0.1f, 0.9f, -2.0f, -0.3f},
                                  {-3.0f, -2.5f, 4.0f, 4.2f}}) {
        for (float h : {0.5f, 1.0f, 7.0f}) {
            // Wound so that (b - a) x (c - a) points down, at the receiver.
            const Vec3f a(x0, h, z0), b(x1, h, z0), c(x1, h, z1), d(x0, h, z1);
            ASSERT_LT(cross(b - a, c - a).y, 0);
            const double exact = parallel_rectangle(h, x0, x1, z0, z1);
            EXPECT_NEAR(quad_irradiance({0, 0, 0}, n, a, b, c, d, false), exact, 2e-6 + 2e-5 * exact);
            EXPECT_NEAR(quad_irradiance({0, 0, 0}, n, a, b, c, d, true), exact, 2e-6 + 2e-5 * exact);
            // Each triangle alone, whole, is non-negative; from behind the light nothing.
            EXPECT_GE(unit_triangle_irradiance({0, 0, 0}, n, a, b, c), 0.0f);
            EXPECT_EQ(unit_triangle_irradiance({0, 2 * h, 0}, -n, a, b, c), 0.0f);
        }
    }
}

TEST(PolygonIrradiance, EmittersAcrossTheHorizonMatchQuadrature) {
    // A 1 m square light facing down at y = 1; receivers tilted so that its horizon cuts it,
    // on a wall below it (normal along x) and beside it.
    const Vec3f a(-0.5f, 1, -0.5f), b(0.5f, 1, -0.5f), c(0.5f, 1, 0.5f), d(-0.5f, 1, 0.5f), ne(0, -1, 0);
    struct Case {
        Vec3f x, n;
    };
    for (const Case& k : {Case{{0, 0, 0}, normalize(Vec3f(1, 0.3f, 0))}, Case{{0.1f, 0.2f, 0.3f}, normalize(Vec3f(0.3f, 0.2f, -1))},
                          Case{{0.2f, 0.5f, 0}, Vec3f(1, 0, 0)}, Case{{-1.0f, 0.9f, 0.2f}, Vec3f(1, 0, 0)}}) {
        const double ref = quadrature(k.x, k.n, a, b, d, ne);
        ASSERT_GT(ref, 1e-3);
        EXPECT_NEAR(quad_irradiance(k.x, k.n, a, b, c, d, false), ref, 2e-4 * ref);
        EXPECT_NEAR(quad_irradiance(k.x, k.n, a, b, c, d, true), ref, 2e-4 * ref);
    }
    // Wholly below the horizon: nothing.
    EXPECT_EQ(quad_irradiance({0, 0, 0}, Vec3f(0, -1, 0), a, b, c, d, false), 0.0f);
}
