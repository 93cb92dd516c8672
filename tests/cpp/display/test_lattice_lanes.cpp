// The baked lattice's lanes (display/lattice_lanes.h) at every width this build has against
// the plain C++ width bit for bit, on a made-up lattice of two geometries and six triangles:
// locate (any lattice), locate16 and blend16 (gathered), light16_cells (one triangle, its
// sub-triangles' affine light); and the gathered blend against the lane loop's, the one-step
// light against the gathered one to float rounding.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "common/lanes.h"
#include "display/baked_lattice.h"
#include "display/lattice_lanes.h"

using namespace gigascroll;
using namespace gigascroll::display;

namespace {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

struct MadeLattice {
    std::vector<std::uint32_t> first_triangle{0, 3}, segments{1, 3, 8, 2, 5, 16};
    std::vector<std::uint64_t> offset;
    std::vector<Vec3f> normal, albedo, emission, front, back;
    BakedLattice b;

    explicit MadeLattice(std::mt19937& rng) {
        std::uniform_real_distribution<float> unit(-1.0f, 1.0f), light(0.0f, 10.0f);
        std::uint64_t points = 0;
        for (std::uint32_t n : segments) {
            offset.push_back(points);
            points += std::uint64_t(n + 1) * (n + 2) / 2;
            normal.push_back(Vec3f{unit(rng), unit(rng), unit(rng)});
            albedo.push_back(Vec3f{0.1f * light(rng), 0.1f * light(rng), 0.1f * light(rng)});
            emission.push_back(Vec3f{light(rng), light(rng), light(rng)});
        }
        for (std::uint64_t k = 0; k < points; ++k) {
            front.push_back(Vec3f{light(rng), light(rng), light(rng)});
            back.push_back(Vec3f{light(rng), light(rng), light(rng)});
        }
        b.first_triangle = first_triangle.data(), b.segments = segments.data(), b.offset = offset.data();
        b.normal = normal.data(), b.albedo = albedo.data(), b.emission = emission.data();
        b.front = front.data(), b.back = back.data();
        b.triangles = segments.size(), b.points = points;
    }
};

struct Packet {
    RTCHit16 h;
    alignas(64) int hit[16];
    alignas(64) std::int32_t back[16];
};

// kind 0: anything (misses, both geometries, barycentrics past the edges, NaN after a miss);
// 1: one triangle, hits only, inside it; 2: one triangle and a small patch of it (one cell
// or a few); 3: one triangle, barycentrics a little outside.
Packet random_packet(std::mt19937& rng, int kind) {
    std::uniform_real_distribution<float> coin(0.0f, 1.0f), unit(-1.0f, 1.0f);
    Packet p;
    std::memset(&p.h, 0, sizeof p.h);
    const unsigned g0 = coin(rng) < 0.5f ? 0 : 1, p0 = unsigned(coin(rng) * 2.99f);
    const bool back0 = coin(rng) < 0.3f;
    const float cu = 0.8f * coin(rng), cv = (1.0f - cu) * coin(rng);
    for (int k = 0; k < 16; ++k) {
        float u = 1.2f * coin(rng) - 0.1f, v = 1.2f * coin(rng) - 0.1f;
        if (kind == 1 || kind == 2) {
            if (kind == 2) u = cu + 0.002f * coin(rng) * float(k), v = cv + 0.001f * coin(rng);
            if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
            u = std::min(std::max(u, 0.0f), 1.0f), v = std::min(std::max(v, 0.0f), 1.0f - u);
        }
        const bool one = kind != 0;
        p.h.geomID[k] = one ? g0 : (coin(rng) < 0.5f ? 0u : 1u);
        p.h.primID[k] = one ? p0 : unsigned(coin(rng) * 2.99f);
        p.h.u[k] = u, p.h.v[k] = v;
        p.h.Ng_x[k] = unit(rng), p.h.Ng_y[k] = unit(rng), p.h.Ng_z[k] = unit(rng);
        if (one) p.h.Ng_x[k] = p.h.Ng_x[0], p.h.Ng_y[k] = p.h.Ng_y[0], p.h.Ng_z[k] = p.h.Ng_z[0];
        p.hit[k] = one || k == 0 || coin(rng) < 0.8f ? -1 : 0;  // the callers have a hit
        if (!p.hit[k] && coin(rng) < 0.5f) p.h.u[k] = std::nanf(""), p.h.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        p.back[k] = one ? back0 : coin(rng) < 0.3f;
    }
    return p;
}

void expect_light_equal(const LaneLight& a, const LaneLight& b, const int* hit, int width, const char* what) {
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 16; ++k) {
            if (hit && !hit[k]) continue;
            ASSERT_TRUE(same_bits(a.E[c][k], b.E[c][k])) << what << " width " << width << " lane " << k;
            ASSERT_TRUE(same_bits(a.a[c][k], b.a[c][k])) << what << " width " << width << " lane " << k;
            ASSERT_TRUE(same_bits(a.M[c][k], b.M[c][k])) << what << " width " << width << " lane " << k;
        }
}

template <int W>
void expect_width_equals_scalar(const BakedLattice& b, const Packet& p) {
    LatticeLanes one, wide;
    // locate, any lattice.
    one.locate<1>(b, p.h, p.hit, p.back);
    wide.locate<W>(b, p.h, p.hit, p.back);
    for (int k = 0; k < 16; ++k) {
        for (int c = 0; c < 3; ++c) {
            ASSERT_TRUE(same_bits(one.weight[c][k], wide.weight[c][k])) << "locate width " << W << " lane " << k;
            ASSERT_EQ(one.corner[c][k], wide.corner[c][k]) << "locate width " << W << " lane " << k;
        }
    }
    // locate16 and blend16, gathered.
    one.locate16<1>(b, p.h, p.hit, p.back);
    wide.locate16<W>(b, p.h, p.hit, p.back);
    ASSERT_EQ(one.hit_lanes, wide.hit_lanes);
    ASSERT_EQ(one.front_lanes & one.hit_lanes, wide.front_lanes & wide.hit_lanes);
    ASSERT_EQ(one.one_triangle, wide.one_triangle);
    ASSERT_EQ(one.one_cell, wide.one_cell);
    for (int k = 0; k < 16; ++k) {
        if (!p.hit[k]) continue;
        for (int c = 0; c < 3; ++c) {
            ASSERT_EQ(one.point[c][k], wide.point[c][k]) << "width " << W << " lane " << k;
            ASSERT_TRUE(same_bits(one.weight[c][k], wide.weight[c][k])) << "width " << W << " lane " << k;
        }
    }
    LaneLight l1, lw;
    one.blend16<1>(b, l1);
    wide.blend16<W>(b, lw);
    expect_light_equal(l1, lw, p.hit, W, "blend16");
    // light16_cells, where it takes the packet.
    LaneLight c1, cw;
    const bool took1 = one.light16_cells<1>(b, p.h, p.back, true, c1);
    const bool tookw = wide.light16_cells<W>(b, p.h, p.back, true, cw);
    ASSERT_EQ(took1, tookw) << "width " << W;
    if (took1) expect_light_equal(c1, cw, nullptr, W, "light16_cells");
}

}  // namespace

TEST(LatticeLanes, EveryWidthEqualsTheScalarLanes) {
    std::mt19937 rng(3);
    const MadeLattice m(rng);
    int one_cell = 0, one_step = 0, gathered = 0;
    for (int i = 0; i < 2000; ++i) {
        const Packet p = random_packet(rng, i % 4);
        // W = 1's gathered blend against the lane loop's (locate and blend).
        LatticeLanes a, g;
        LaneLight la, lg;
        a.locate<1>(m.b, p.h, p.hit, p.back);
        a.blend(m.b, la);
        g.locate16<1>(m.b, p.h, p.hit, p.back);
        g.blend16<1>(m.b, lg);
        expect_light_equal(la, lg, p.hit, 1, "blend16 against blend");
        one_cell += g.one_cell, gathered += !g.one_triangle;
        // The one-step light against the gathered one, to float rounding.
        LaneLight lc;
        if (g.light16_cells<1>(m.b, p.h, p.back, true, lc)) {
            ++one_step;
            for (int c = 0; c < 3; ++c)
                for (int k = 0; k < 16; ++k) {
                    ASSERT_NEAR(lc.E[c][k], lg.E[c][k], 1e-5f * (1.0f + std::abs(lg.E[c][k]))) << k;
                    ASSERT_EQ(lc.a[c][k], lg.a[c][k]);
                    ASSERT_EQ(lc.M[c][k], lg.M[c][k]);
                }
        }
#if defined(__AVX2__)
        expect_width_equals_scalar<8>(m.b, p);
#endif
#if defined(__AVX512F__)
        expect_width_equals_scalar<16>(m.b, p);
#endif
    }
    // Every path ran.
    EXPECT_GT(one_cell, 50);
    EXPECT_GT(one_step, 200);
    EXPECT_GT(gathered, 200);
}
