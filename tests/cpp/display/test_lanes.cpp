// The lane type (common/lanes.h) at every width this build has: a step written
// once on Lanes<W> must give the plain C++ width's bits at 8 (AVX2) and 16 (AVX-512) lanes.
// The right eye's claim projection (ClaimProjection::project) is the step: random hits around a
// stereo pair, with misses, hits behind the eye, outside the image, facing away and NaN normals.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "common/lanes.h"
#include "display/stereo_reuse.h"
#include "views/camera.h"

using namespace gigascroll;
using namespace gigascroll::display;

namespace {

struct Packet {
    alignas(64) float px[16], py[16], pz[16], nx[16], ny[16], nz[16];
    alignas(64) int hit[16];
};

Packet random_packet(std::mt19937& rng) {
    std::uniform_real_distribution<float> pos(-3.0f, 3.0f), unit(-1.0f, 1.0f), coin(0.0f, 1.0f);
    Packet p;
    for (int k = 0; k < 16; ++k) {
        p.px[k] = pos(rng), p.py[k] = pos(rng) + 1.5f, p.pz[k] = pos(rng) + 2.0f;
        p.nx[k] = unit(rng), p.ny[k] = unit(rng), p.nz[k] = unit(rng);
        if (coin(rng) < 0.05f) p.nx[k] = std::nanf("");
        p.hit[k] = coin(rng) < 0.9f ? -1 : 0;
    }
    return p;
}

template <int W>
void expect_width_equals_scalar(const ClaimProjection& c, const Packet& p) {
    alignas(64) std::uint32_t t1[16], tw[16];
    alignas(64) float d1[16], dw[16];
    c.project<1>(p.px, p.py, p.pz, p.nx, p.ny, p.nz, p.hit, t1, d1);
    c.project<W>(p.px, p.py, p.pz, p.nx, p.ny, p.nz, p.hit, tw, dw);
    for (int k = 0; k < 16; ++k) {
        ASSERT_EQ(t1[k], tw[k]) << "width " << W << " lane " << k;
        ASSERT_EQ(std::memcmp(&d1[k], &dw[k], sizeof(float)), 0) << "width " << W << " lane " << k;
    }
}

}  // namespace

TEST(Lanes, ClaimProjectionIsTheSameAtEveryWidth) {
    const Camera right({0.032, 1.5, -0.5}, {0, 0, 1}, {0, 1, 0}, 0.6, 0.6 * 37 / 53, 53, 37);
    std::vector<std::uint64_t> claims(53 * 37, kUnclaimed);
    const ClaimProjection c(right, claims.data());
    std::mt19937 rng(42);
    int claimed = 0, refused = 0;
    for (int i = 0; i < 2000; ++i) {
        const Packet p = random_packet(rng);
        alignas(64) std::uint32_t target[16];
        alignas(64) float depth[16];
        c.project<1>(p.px, p.py, p.pz, p.nx, p.ny, p.nz, p.hit, target, depth);
        for (int k = 0; k < 16; ++k) (target[k] == ClaimProjection::kNoTarget ? refused : claimed) += 1;
        // Against Camera::project (VR-photon-mapping eqs. 3-5) for a claimed lane.
        for (int k = 0; k < 16; ++k) {
            if (target[k] == ClaimProjection::kNoTarget) continue;
            const Vec3d q = Vec3d(p.px[k], p.py[k], p.pz[k]) - right.position;
            const double z = dot(q, right.forward);
            const double x = (dot(q, right.right) / (z * right.tan_half_x) + 1) * 0.5 * right.width;
            const double y = (1 - dot(q, right.up) / (z * right.tan_half_y)) * 0.5 * right.height;
            ASSERT_NEAR(double(target[k] % right.width) + 0.5, x, 0.5 + 1e-3);
            ASSERT_NEAR(double(target[k] / right.width) + 0.5, y, 0.5 + 1e-3);
        }
#if defined(__AVX2__)
        expect_width_equals_scalar<8>(c, p);
#endif
#if defined(__AVX512F__)
        expect_width_equals_scalar<16>(c, p);
#endif
    }
    EXPECT_GT(claimed, 1000);
    EXPECT_GT(refused, 1000);
}

TEST(Lanes, WidestIsWhatTheBuildHas) {
#if defined(__AVX512F__)
    EXPECT_EQ(kWidest, 16);
#elif defined(__AVX2__)
    EXPECT_EQ(kWidest, 8);
#else
    EXPECT_EQ(kWidest, 1);
#endif
}
