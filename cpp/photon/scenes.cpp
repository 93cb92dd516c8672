#include "photon/scenes.h"

#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "common/error.h"

namespace gigascroll {

namespace {

using Mat34 = std::array<float, 12>;  // row-major 3x4 affine transform

Vec3f apply(const Mat34& m, Vec3f p) {
    return {m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
            m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]};
}

// Accumulates triangles with per-triangle albedo; flushed into the Scene as one mesh.
struct MeshBuilder {
    std::vector<float> v;
    std::vector<std::int64_t> t;
    std::vector<float> albedo;

    std::int64_t vertex(Vec3f p) {
        v.insert(v.end(), {p.x, p.y, p.z});
        return std::int64_t(v.size() / 3 - 1);
    }
    void tri(std::int64_t a, std::int64_t b, std::int64_t c, Vec3f al) {
        t.insert(t.end(), {a, b, c});
        albedo.insert(albedo.end(), {al.x, al.y, al.z});
    }
    void quad(Vec3f a, Vec3f b, Vec3f c, Vec3f d, Vec3f al) {  // counter-clockwise seen from the front
        const auto i = vertex(a), j = vertex(b), k = vertex(c), l = vertex(d);
        tri(i, j, k, al);
        tri(k, l, i, al);
    }
    // Mitsuba's `rectangle`: [-1, 1]^2 at z = 0, normal +z, under transform m.
    void rectangle(const Mat34& m, Vec3f al) {
        quad(apply(m, {-1, -1, 0}), apply(m, {1, -1, 0}), apply(m, {1, 1, 0}), apply(m, {-1, 1, 0}), al);
    }
    // Mitsuba's `cube`: [-1, 1]^3 with outward normals, under transform m.
    void cube(const Mat34& m, Vec3f al) {
        for (int axis = 0; axis < 3; ++axis)
            for (int sign = -1; sign <= 1; sign += 2) {
                Vec3f n{0, 0, 0}, u{0, 0, 0}, w{0, 0, 0};
                n[axis] = float(sign);
                u[(axis + 1) % 3] = 1;
                w[(axis + 2) % 3] = 1;
                if (sign < 0) std::swap(u, w);  // keep u x w = n
                quad(apply(m, n - u - w), apply(m, n + u - w), apply(m, n + u + w), apply(m, n - u + w), al);
            }
    }
    // Axis-aligned box from its centre and half extents, rotated by `yaw` radians about y.
    void box(Vec3f c, Vec3f half, Vec3f al, float yaw = 0) {
        const float cs = std::cos(yaw), sn = std::sin(yaw);
        cube({cs * half.x, 0, sn * half.z, c.x, 0, half.y, 0, c.y, -sn * half.x, 0, cs * half.z, c.z}, al);
    }
    // Closed cylinder along y from base centre c.
    void cylinder(Vec3f c, float r, float height, int segs, Vec3f al) {
        const auto top = vertex(c + Vec3f(0, height, 0)), bottom = vertex(c);
        std::vector<std::int64_t> lo(segs), hi(segs);
        for (int i = 0; i < segs; ++i) {
            const float a = 2.0f * float(M_PI) * float(i) / float(segs);
            const Vec3f o{r * std::cos(a), 0, -r * std::sin(a)};
            lo[i] = vertex(c + o);
            hi[i] = vertex(c + o + Vec3f(0, height, 0));
        }
        for (int i = 0; i < segs; ++i) {
            const int j = (i + 1) % segs;
            tri(lo[i], lo[j], hi[j], al);
            tri(hi[j], hi[i], lo[i], al);
            tri(top, hi[i], hi[j], al);
            tri(bottom, lo[j], lo[i], al);
        }
    }
    // Latitude-longitude sphere; inward = true winds the normals toward the centre.
    void sphere(Vec3f c, float r, int nu, int nv, Vec3f al, bool inward = false) {
        const std::int64_t base = std::int64_t(v.size() / 3);
        for (int j = 0; j <= nv; ++j)
            for (int i = 0; i <= nu; ++i) {
                const float th = float(M_PI) * float(j) / float(nv), ph = 2.0f * float(M_PI) * float(i) / float(nu);
                vertex(c + Vec3f(std::sin(th) * std::cos(ph), std::cos(th), -std::sin(th) * std::sin(ph)) * r);
            }
        auto id = [&](int i, int j) { return base + std::int64_t(j) * (nu + 1) + i; };
        for (int j = 0; j < nv; ++j)
            for (int i = 0; i < nu; ++i) {
                std::int64_t a = id(i, j), b = id(i, j + 1), cc = id(i + 1, j + 1), d = id(i + 1, j);
                if (inward) std::swap(b, d);
                if (j > 0) tri(a, b, cc, al);
                if (j < nv - 1) tri(cc, d, a, al);
            }
    }
    // A floor-like rectangle tessellated into nx x nz quads, normal +y.
    void grid_y(float x0, float x1, float z0, float z1, float y, int nx, int nz, Vec3f al, Vec3f al2) {
        for (int j = 0; j < nz; ++j)
            for (int i = 0; i < nx; ++i) {
                const float xa = x0 + (x1 - x0) * float(i) / float(nx), xb = x0 + (x1 - x0) * float(i + 1) / float(nx);
                const float za = z0 + (z1 - z0) * float(j) / float(nz), zb = z0 + (z1 - z0) * float(j + 1) / float(nz);
                const bool checker = ((i / 8) + (j / 8)) % 2 == 0;  // carpet tiles
                quad({xa, y, zb}, {xb, y, zb}, {xb, y, za}, {xa, y, za}, checker ? al : al2);
            }
    }
    std::size_t flush(Scene& scene, Vec3f emission = {0, 0, 0}) {
        if (t.empty()) return 0;
        const std::size_t n = scene.add_mesh(v.data(), v.size() / 3, t.data(), t.size() / 3, albedo.data(),
                                             true, emission);
        v.clear();
        t.clear();
        albedo.clear();
        return n;
    }
};

}  // namespace

Camera build_cornell(Scene& scene, int width, int height) {
    // Transforms, reflectances and radiance exactly as printed by mitsuba.cornell_box().
    const Vec3f white{0.885809f, 0.698859f, 0.666422f};
    const Vec3f red{0.570068f, 0.0430135f, 0.0443706f};
    const Vec3f green{0.105421f, 0.37798f, 0.076425f};
    const float e = -4.37114e-08f;
    MeshBuilder mb;
    mb.rectangle({1, 0, 0, 0, 0, e, 1, -1, 0, -1, e, 0}, white);    // floor
    mb.rectangle({1, 0, 0, 0, 0, e, -1, 1, 0, 1, e, 0}, white);     // ceiling
    mb.rectangle({1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, -1}, white);     // back
    mb.rectangle({e, 0, -1, 1, 0, 1, 0, 0, 1, 0, e, 0}, green);     // green wall (x = +1)
    mb.rectangle({e, 0, 1, -1, 0, 1, 0, 0, -1, 0, e, 0}, red);      // red wall (x = -1)
    mb.cube({0.28491f, 0, 0.0939491f, -0.33f, 0, 0.61f, 0, -0.4f, -0.0939491f, 0, 0.28491f, -0.28f}, white);
    mb.cube({0.286891f, 0, -0.0877115f, 0.335f, 0, 0.3f, 0, -0.7f, 0.0877115f, 0, 0.286891f, 0.38f}, white);
    mb.flush(scene);
    mb.rectangle({0.23f, 0, 0, 0, 0, -8.30516e-09f, -0.19f, 0.99f, 0, 0.19f, -8.30516e-09f, 0.01f}, white);
    mb.flush(scene, {18.387f, 13.9873f, 6.75357f});
    return Camera::look_at({0, 0, 3.9f}, {0, 0, 0}, {0, 1, 0}, 39.3077f, width, height);
}

Camera build_furnace(Scene& scene, float albedo, float emission, int width, int height) {
    require(std::isfinite(emission) && emission > 0, "furnace: emission must be positive");
    MeshBuilder mb;
    mb.sphere({0, 0, 0}, 1.0f, 96, 48, {albedo, albedo, albedo}, /*inward=*/true);
    mb.flush(scene, {emission, emission, emission});
    return Camera::look_at({0, 0, 0}, {0, 0, -1}, {0, 1, 0}, 60.0f, width, height);
}

Camera build_office(Scene& scene, int width, int height) {
    // A room 8 m x 3 m x 6 m: x in [-4, 4], y in [0, 3], z in [-3, 3].
    const Vec3f wall{0.72f, 0.70f, 0.65f}, ceiling{0.8f, 0.8f, 0.8f};
    const Vec3f carpet{0.25f, 0.28f, 0.33f}, carpet2{0.30f, 0.31f, 0.35f};
    const Vec3f wood{0.55f, 0.38f, 0.22f}, metal{0.45f, 0.45f, 0.47f}, dark{0.05f, 0.05f, 0.06f};
    const Vec3f fabric{0.20f, 0.25f, 0.55f}, keycap{0.80f, 0.80f, 0.78f}, screen{0.02f, 0.02f, 0.03f};
    MeshBuilder mb;
    // Walls and ceiling, facing inward.
    mb.quad({-4, 0, -3}, {4, 0, -3}, {4, 3, -3}, {-4, 3, -3}, wall);   // back, normal +z
    mb.quad({4, 0, 3}, {-4, 0, 3}, {-4, 3, 3}, {4, 3, 3}, wall);       // front, normal -z
    mb.quad({-4, 0, 3}, {-4, 0, -3}, {-4, 3, -3}, {-4, 3, 3}, wall);   // left, normal +x
    mb.quad({4, 0, -3}, {4, 0, 3}, {4, 3, 3}, {4, 3, -3}, wall);       // right, normal -x
    mb.quad({-4, 3, -3}, {4, 3, -3}, {4, 3, 3}, {-4, 3, 3}, ceiling);  // ceiling, normal -y

    // Workstations: 3 rows x 4 desks.
    for (int row = 0; row < 3; ++row)
        for (int col = 0; col < 4; ++col) {
            const float cx = -2.7f + 1.8f * float(col), cz = -1.9f + 1.7f * float(row);
            mb.box({cx, 0.74f, cz}, {0.7f, 0.02f, 0.4f}, wood);  // desk top
            for (int lx = -1; lx <= 1; lx += 2)
                for (int lz = -1; lz <= 1; lz += 2)
                    mb.box({cx + 0.65f * float(lx), 0.36f, cz + 0.35f * float(lz)}, {0.025f, 0.36f, 0.025f}, metal);
            // Monitor: stand, neck, panel with a dark screen.
            mb.box({cx, 0.765f, cz - 0.25f}, {0.12f, 0.005f, 0.08f}, metal);
            mb.box({cx, 0.9f, cz - 0.28f}, {0.02f, 0.14f, 0.02f}, metal);
            mb.box({cx, 1.1f, cz - 0.27f}, {0.3f, 0.18f, 0.015f}, dark);
            mb.box({cx, 1.1f, cz - 0.254f}, {0.285f, 0.165f, 0.001f}, screen);
            // Keyboard: a base and 6 x 17 keys.
            mb.box({cx, 0.77f, cz + 0.1f}, {0.22f, 0.01f, 0.07f}, dark);
            for (int kr = 0; kr < 6; ++kr)
                for (int kc = 0; kc < 17; ++kc)
                    mb.box({cx - 0.2f + 0.025f * float(kc), 0.785f, cz + 0.045f + 0.021f * float(kr)},
                           {0.0105f, 0.006f, 0.0085f}, keycap);
            // Mouse.
            mb.sphere({cx + 0.32f, 0.77f, cz + 0.1f}, 0.025f, 24, 12, dark);
            // Chair: five legs with wheels, a post, a seat and a back.
            const Vec3f chair{cx, 0, cz + 0.7f};
            for (int leg = 0; leg < 5; ++leg) {
                const float a = 2.0f * float(M_PI) * float(leg) / 5.0f;
                const Vec3f dir{std::cos(a), 0, std::sin(a)};
                mb.box(chair + dir * 0.15f + Vec3f(0, 0.07f, 0), {0.15f, 0.015f, 0.02f}, metal, -a);
                mb.sphere(chair + dir * 0.3f + Vec3f(0, 0.03f, 0), 0.03f, 48, 24, dark);
            }
            mb.cylinder(chair + Vec3f(0, 0.08f, 0), 0.03f, 0.35f, 48, metal);
            mb.box(chair + Vec3f(0, 0.45f, 0), {0.23f, 0.04f, 0.23f}, fabric);
            mb.box(chair + Vec3f(0, 0.8f, 0.22f), {0.22f, 0.28f, 0.03f}, fabric);
        }
    // Shelves along the back wall with books.
    int book = 0;
    for (int unit = 0; unit < 4; ++unit) {
        const float sx = -3.0f + 2.0f * float(unit);
        for (int s = 0; s < 5; ++s) {
            const float sy = 0.3f + 0.45f * float(s);
            mb.box({sx, sy, -2.8f}, {0.8f, 0.015f, 0.18f}, wood);
            float x = sx - 0.78f;
            while (x < sx + 0.7f) {
                const float wdt = 0.02f + 0.015f * float((book * 7) % 5) / 4.0f;
                const float hgt = 0.14f + 0.08f * float((book * 3) % 7) / 6.0f;
                const Vec3f col{0.15f + 0.6f * float((book * 5) % 7) / 6.0f, 0.1f + 0.5f * float((book * 3) % 5) / 4.0f,
                               0.1f + 0.6f * float((book * 11) % 9) / 8.0f};
                mb.box({x + wdt, sy + 0.015f + hgt / 2, -2.78f}, {wdt * 0.95f, hgt / 2, 0.13f}, col);
                x += 2 * wdt + 0.002f;
                ++book;
            }
        }
        for (int side = -1; side <= 1; side += 2)
            mb.box({sx + 0.82f * float(side), 1.2f, -2.8f}, {0.02f, 1.2f, 0.18f}, wood);
    }
    // A plant in the corner: pot and a dense canopy.
    mb.cylinder({3.5f, 0, 2.5f}, 0.2f, 0.4f, 64, {0.5f, 0.3f, 0.2f});
    mb.sphere({3.5f, 0.9f, 2.5f}, 0.45f, 256, 128, {0.1f, 0.4f, 0.1f});
    // Carpet tessellated to bring the total to about 710k triangles, like the seed's office.
    const std::size_t others = mb.t.size() / 3;
    const std::size_t want = 716500 > others ? 716500 - others : 0;
    const int nz = std::max(1, int(std::sqrt(double(want) / 2.0 * 6.0 / 8.0)));
    const int nx = std::max(1, int(double(want) / 2.0 / nz));
    mb.grid_y(-4, 4, -3, 3, 0, nx, nz, carpet, carpet2);
    mb.flush(scene);
    // Ceiling panels (white) and a coloured desk lamp (orange shade).
    for (int i = -1; i <= 1; i += 2)
        for (int j = -1; j <= 1; j += 2)
            mb.quad({2.0f * i - 0.6f, 2.99f, 1.5f * j - 0.3f}, {2.0f * i + 0.6f, 2.99f, 1.5f * j - 0.3f},
                    {2.0f * i + 0.6f, 2.99f, 1.5f * j + 0.3f}, {2.0f * i - 0.6f, 2.99f, 1.5f * j + 0.3f},
                    {0.8f, 0.8f, 0.8f});
    mb.flush(scene, {8.0f, 7.6f, 7.0f});
    mb.cylinder({-2.3f, 0.76f, -2.1f}, 0.01f, 0.35f, 16, metal);
    mb.flush(scene);
    mb.sphere({-2.3f, 1.15f, -2.1f}, 0.07f, 32, 16, {0.8f, 0.5f, 0.2f});
    mb.flush(scene, {30.0f, 12.0f, 3.0f});
    return Camera::look_at({0.3f, 1.6f, 2.8f}, {-0.3f, 0.8f, -1.5f}, {0, 1, 0}, 60.0f, width, height);
}

Camera build_scene(const std::string& name, Scene& scene, int width, int height, float albedo,
                   float emission) {
    if (name == "cornell") return build_cornell(scene, width, height);
    if (name == "office") return build_office(scene, width, height);
    if (name == "furnace") return build_furnace(scene, albedo, emission, width, height);
    throw InvalidArgument("unknown scene '" + name + "' (built-in: cornell, office, furnace)");
}

}  // namespace gigascroll
