// The display pass's lane steps at every width this build has (common/lanes.h: W = 1, 8, 16)
// against the plain C++ width bit for bit, and the functions the lane type keeps apart (the
// float classes, the hardware's estimates, the table lookup, the masked store) against their
// W = 1 twins; the plane map's packet also against its per-pixel double form, and the
// stereo reuse's release of claims against its definition.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "common/lanes.h"
#include "display/plane_map.h"
#include "display/shade.h"
#include "display/srgb.h"
#include "display/stereo_reuse.h"
#include "views/camera.h"

using namespace gigascroll;
using namespace gigascroll::display;

namespace {

bool same_bits(float a, float b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// 64 floats that reach the lane functions' corners: signed zeros, subnormals, infinities,
// NaN, the largest and smallest normals, and random values over many magnitudes.
std::vector<float> awkward_floats(std::mt19937& rng) {
    const float inf = std::numeric_limits<float>::infinity();
    std::vector<float> v = {0.0f, -0.0f, 1e-40f, -1e-40f, inf, -inf, std::nanf(""), 1.0f,
                            std::numeric_limits<float>::max(), std::numeric_limits<float>::min(), 2.0f, 0.5f,
                            1.4142135f, 1.4142137f, 3.0f, 255.0f};
    std::uniform_real_distribution<float> e(-30.0f, 30.0f), sign(-1.0f, 1.0f);
    while (v.size() < 64) v.push_back((sign(rng) < 0 ? -1.0f : 1.0f) * std::exp2(e(rng)));
    return v;
}

template <int W>
void expect_functions_equal_twins(const std::vector<float>& x) {
    using F = typename Lanes<W>::F;
    using I = typename Lanes<W>::I;
    alignas(64) static const float table[16] = {3, 1, 4, 1, 5, 9, 2, 6, 5, 3, 5, 8, 9, 7, 9, 3};
    for (std::size_t k0 = 0; k0 < x.size(); k0 += W) {
        const F v = F::load(x.data() + k0);
        const unsigned normal = not_positive_normal(v).bits(), finite = not_finite(v).bits();
        alignas(64) float rcp[W], rsq[W], looked[W], stored[W + 1];
        reciprocal(v).store(rcp);
        rsqrt_estimate(v).store(rsq);
        alignas(64) std::int32_t index[W];
        for (int k = 0; k < W; ++k) index[k] = std::int32_t((k0 + 5 * k) % 16);
        lookup16(table, I::load(index)).store(looked);
        for (int k = 0; k < W; ++k) {
            const Lanes<1>::F s(x[k0 + k]);
            ASSERT_EQ((normal >> k) & 1, not_positive_normal(s).bits()) << "width " << W << " x " << s.v;
            ASSERT_EQ((finite >> k) & 1, not_finite(s).bits()) << "width " << W << " x " << s.v;
            ASSERT_TRUE(same_bits(rcp[k], reciprocal(s).v)) << "width " << W << " x " << s.v;
            ASSERT_TRUE(same_bits(rsq[k], rsqrt_estimate(s).v)) << "width " << W << " x " << s.v;
            ASSERT_EQ(looked[k], table[index[k]]);
        }
        // The first n lanes stored, the rest left as they were.
        for (unsigned n = 0; n <= unsigned(W); n += (W > 1 ? 3 : 1)) {
            for (float& s : stored) s = -7.0f;
            store_first(v, stored, n);
            for (unsigned k = 0; k <= unsigned(W); ++k)
                ASSERT_TRUE(same_bits(stored[k], k < n ? x[k0 + k] : -7.0f)) << "width " << W << " n " << n;
        }
    }
}

}  // namespace

TEST(LaneFunctions, EveryWidthEqualsItsScalarTwin) {
    std::mt19937 rng(7);
    const std::vector<float> x = awkward_floats(rng);
    // The twins against the definitions they stand for.
    for (float s : x) {
        const bool positive_normal = std::isnormal(s) && s > 0;
        EXPECT_EQ(not_positive_normal(Lanes<1>::F(s)).bits(), positive_normal ? 0u : 1u) << s;
        EXPECT_EQ(not_finite(Lanes<1>::F(s)).bits(), std::isfinite(s) ? 0u : 1u) << s;
        if (positive_normal && s < 1e30f && s > 1e-30f) {
            EXPECT_NEAR(reciprocal(Lanes<1>::F(s)).v * s, 1.0f, 1e-7f) << s;
            EXPECT_NEAR(rsqrt_estimate(Lanes<1>::F(s)).v * std::sqrt(s), 1.0f, 1e-3f) << s;
            EXPECT_NEAR(inverse_sqrt(s) * std::sqrt(s), 1.0f, 3e-7f) << s;
        }
    }
#if defined(__AVX2__)
    expect_functions_equal_twins<8>(x);
#endif
#if defined(__AVX512F__)
    expect_functions_equal_twins<16>(x);
#endif
}

namespace {

struct ShadeInputs {
    alignas(64) float tex[3][16], E[3][16], M[3][16], sq[16];
    LaneLight light;
};

ShadeInputs random_shade_inputs(std::mt19937& rng) {
    std::uniform_real_distribution<float> code(-2.0f, 258.0f), light(0.0f, 40.0f), positive(1e-3f, 1e3f);
    ShadeInputs s;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 16; ++k) {
            s.tex[c][k] = code(rng), s.E[c][k] = light(rng), s.M[c][k] = 0.01f * light(rng);
            s.light.E[c][k] = light(rng), s.light.a[c][k] = 0.01f * light(rng), s.light.M[c][k] = 0.1f * light(rng);
        }
    for (int k = 0; k < 16; ++k) s.sq[k] = positive(rng);
    return s;
}

// shade_packet, shade_room_packet and inverse_sqrt_16 at W lanes against W = 1, whole and
// short packets (the pixels past n untouched).
template <int W>
void expect_shade_equals_scalar(const ShadeInputs& s, const DisplayOptions& o, std::uint32_t n) {
    alignas(64) float rgb1[49], rgbw[49], lod1[17], lodw[17], sq1[16], sqw[16];
    for (int k = 0; k < 49; ++k) rgb1[k] = rgbw[k] = -5.0f;
    for (int k = 0; k < 17; ++k) lod1[k] = lodw[k] = -5.0f;
    shade_packet<1>(s.tex, s.E, s.M, o, srgb_curve(), rgb1, n);
    shade_packet<W>(s.tex, s.E, s.M, o, srgb_curve(), rgbw, n);
    for (int k = 0; k < 49; ++k) ASSERT_TRUE(same_bits(rgb1[k], rgbw[k])) << "width " << W << " n " << n << " at " << k;
    for (int k = 0; k < 49; ++k) rgb1[k] = rgbw[k] = -5.0f;
    shade_room_packet<1>(s.light, rgb1, lod1, n);
    shade_room_packet<W>(s.light, rgbw, lodw, n);
    for (int k = 0; k < 49; ++k) ASSERT_TRUE(same_bits(rgb1[k], rgbw[k])) << "width " << W << " n " << n << " at " << k;
    for (int k = 0; k < 17; ++k) ASSERT_TRUE(same_bits(lod1[k], lodw[k])) << "width " << W << " n " << n << " at " << k;
    std::memcpy(sq1, s.sq, sizeof sq1), std::memcpy(sqw, s.sq, sizeof sqw);
    inverse_sqrt_16<1>(sq1), inverse_sqrt_16<W>(sqw);
    for (int k = 0; k < 16; ++k) ASSERT_TRUE(same_bits(sq1[k], sqw[k])) << "width " << W;
}

}  // namespace

TEST(ShadeLanes, EveryWidthEqualsTheScalarShade) {
    std::mt19937 rng(11);
    DisplayOptions o;
    o.painting_reflectance = 0.85f;
    for (int i = 0; i < 200; ++i) {
        const ShadeInputs s = random_shade_inputs(rng);
        o.srgb_albedo = i % 2 == 0;
        const std::uint32_t n = i % 4 == 0 ? std::uint32_t(1 + i % 15) : 16;
        // W = 1 against the arithmetic it says: the first pixel's red.
        alignas(64) float rgb[48];
        shade_packet<1>(s.tex, s.E, s.M, o, srgb_curve(), rgb, n);
        const float albedo = (o.srgb_albedo ? srgb_curve()(s.tex[0][0]) : s.tex[0][0] / 255.0f) * 0.85f;
        ASSERT_NEAR(rgb[0], albedo * s.E[0][0] / 3.14159265f + s.M[0][0], 1e-4f * (1.0f + rgb[0]));
#if defined(__AVX2__)
        expect_shade_equals_scalar<8>(s, o, n);
#endif
#if defined(__AVX512F__)
        expect_shade_equals_scalar<16>(s, o, n);
#endif
    }
}

namespace {

// A 2 x 1.5 m painting of 6000 x 4500 texels in the plane z = 3, seen from eyes around it.
PaintingPlacement test_painting() {
    return {0, PaintingGeometry(6000, 4500), {-1.0, 0.5, 3.0}, {1, 0, 0}, {0, 1, 0}, 2.0, 1.5};
}

template <int W>
void expect_map_equals_scalar(const PlaneMap& map, const PlaneMap::Row& row, double s0, const float* ds) {
    PacketUv a, b;
    const bool ok1 = map.map_packet<1>(row, s0, ds, 0.25f, a), okw = map.map_packet<W>(row, s0, ds, 0.25f, b);
    ASSERT_EQ(ok1, okw) << "width " << W;
    if (!ok1) return;
    ASSERT_EQ(a.u0, b.u0);
    ASSERT_EQ(a.v0, b.v0);
    for (int k = 0; k < 16; ++k) {
        ASSERT_TRUE(same_bits(a.du[k], b.du[k])) << "width " << W << " lane " << k;
        ASSERT_TRUE(same_bits(a.dv[k], b.dv[k])) << "width " << W << " lane " << k;
        ASSERT_TRUE(same_bits(a.lod[k], b.lod[k])) << "width " << W << " lane " << k;
    }
}

}  // namespace

TEST(PlaneMapLanes, PacketsAtEveryWidthEqualTheScalarAndFollowThePixels) {
    const PaintingPlacement pp = test_painting();
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> pos(-2.0, 2.0);
    int mapped = 0;
    for (int i = 0; i < 300; ++i) {
        const Vec3d eye{pos(rng), 0.5 + 0.5 * pos(rng), -1.0 + 0.5 * pos(rng)};
        // Towards the painting (centre (0, 1.25, 3)); every tenth view along its plane.
        const Vec3d target = i % 10 == 0 ? eye + Vec3d{1, 0, 0.001}
                                         : Vec3d{0.5 * pos(rng), 1.25 + 0.3 * pos(rng), 3.0};
        const Camera cam = Camera::look_at(eye, target, {0, 1, 0}, 70.0, 640, 480);
        const PlaneMap map(pp, cam);
        const std::uint32_t x0 = std::uint32_t(212 + i * 37 % 200), y = std::uint32_t(140 + i * 53 % 200);  // near the target
        const double sy = cam.screen_y(y + 0.5);
        const PlaneMap::Row row = map.row(cam.forward + sy * cam.up, cam.right);
        const double s0 = cam.screen_x(x0 + 0.5);
        alignas(64) double sx[16], u[16], v[16];
        alignas(64) float ds[16], lod[16];
        for (int k = 0; k < 16; ++k) sx[k] = cam.screen_x(x0 + k + 0.5), ds[k] = float(sx[k] - s0);
#if defined(__AVX2__)
        expect_map_equals_scalar<8>(map, row, s0, ds);
#endif
#if defined(__AVX512F__)
        expect_map_equals_scalar<16>(map, row, s0, ds);
#endif
        // Against the per-pixel map in double: uv (unclamped, where inside) and level.
        PacketUv p;
        if (!map.map_packet<1>(row, s0, ds, 0.25f, p)) continue;
        map.map_columns<true>(row, 16, sx, u, v, lod);
        for (int k = 0; k < 16; ++k) {
            const double uk = p.u0 + p.du[k], vk = p.v0 + p.dv[k];
            if (uk > 0 && uk < 1 && vk > 0 && vk < 1) {
                ASSERT_NEAR(uk, u[k], 1e-6 + 1e-5 * std::abs(p.du[k]));
                ASSERT_NEAR(vk, v[k], 1e-6 + 1e-5 * std::abs(p.dv[k]));
                ++mapped;
            }
            if (std::isfinite(lod[k])) ASSERT_NEAR(p.lod[k], sampled_lod(lod[k], 0.25f), 1e-4f) << k;
        }
    }
    EXPECT_GT(mapped, 1000);  // the comparison with the pixels ran
}

namespace {

template <int W>
void expect_release_equals_scalar(const std::vector<std::uint64_t>& claims, const std::vector<float>& up,
                                  const std::vector<float>& mid, const std::vector<float>& down, float ratio) {
    const std::size_t w = claims.size();
    std::vector<std::int32_t> s1(w, 7), sw(w, 7);
    std::uint64_t kept1 = 0, keptw = 0;
    ASSERT_EQ(release_claim_lanes<1>(claims.data(), up.data(), mid.data(), down.data(), w, ratio, s1.data(), kept1), w);
    const std::size_t x = release_claim_lanes<W>(claims.data(), up.data(), mid.data(), down.data(), w, ratio, sw.data(), keptw);
    ASSERT_EQ(x, w - w % W);
    std::uint64_t kept_head = 0;
    for (std::size_t k = 0; k < x; ++k) {
        ASSERT_EQ(s1[k], sw[k]) << "width " << W << " claim " << k;
        kept_head += s1[k] >= 0;
    }
    ASSERT_EQ(keptw, kept_head);
    for (std::size_t k = x; k < w; ++k) ASSERT_EQ(sw[k], 7);  // not taken
}

}  // namespace

TEST(ReleaseLanes, EveryWidthEqualsTheScalarRelease) {
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> depth(0.5f, 8.0f), coin(0.0f, 1.0f);
    const float inf = std::numeric_limits<float>::infinity();
    for (std::size_t w : {1u, 7u, 16u, 37u, 100u}) {
        std::vector<std::uint64_t> claims(w);
        std::vector<float> up(w), mid(w), down(w);
        for (std::size_t k = 0; k < w; ++k) {
            const float d = depth(rng);
            claims[k] = coin(rng) < 0.2f ? kUnclaimed
                                         : (std::uint64_t(std::bit_cast<std::uint32_t>(d)) << 32 | std::uint64_t(k * 977));
            up[k] = coin(rng) < 0.1f ? inf : depth(rng), mid[k] = depth(rng), down[k] = depth(rng);
        }
        // The scalar release against its definition (release_claims' comment).
        std::vector<std::int32_t> source(w);
        std::uint64_t kept = 0;
        release_claim_lanes<1>(claims.data(), up.data(), mid.data(), down.data(), w, 1.05f, source.data(), kept);
        std::uint64_t want_kept = 0;
        for (std::size_t k = 0; k < w; ++k) {
            const float nearest = std::min({up[k], mid[k], down[k]});
            const bool keep = claims[k] != kUnclaimed && std::bit_cast<float>(std::uint32_t(claims[k] >> 32)) <= nearest * 1.05f;
            ASSERT_EQ(source[k], keep ? std::int32_t(k * 977) : -1) << k;
            want_kept += keep;
        }
        ASSERT_EQ(kept, want_kept);
#if defined(__AVX2__)
        expect_release_equals_scalar<8>(claims, up, mid, down, 1.05f);
#endif
#if defined(__AVX512F__)
        expect_release_equals_scalar<16>(claims, up, mid, down, 1.05f);
#endif
    }
}

TEST(ReleaseLanes, ClaimedRowMinimaAreTheThreeNeighboursMinimum) {
    std::mt19937 rng(19);
    std::uniform_real_distribution<float> depth(0.5f, 8.0f), coin(0.0f, 1.0f);
    const float inf = std::numeric_limits<float>::infinity();
    for (std::size_t w : {1u, 2u, 15u, 16u, 17u, 40u, 333u}) {
        std::vector<std::uint64_t> claims(w);
        for (std::size_t k = 0; k < w; ++k)
            claims[k] = coin(rng) < 0.3f ? kUnclaimed
                                         : (std::uint64_t(std::bit_cast<std::uint32_t>(depth(rng))) << 32 | std::uint64_t(k));
        std::vector<float> depths(w + 2), row_min(w);
        claimed_row_min(claims.data(), w, depths.data(), row_min.data());
        auto at = [&](std::ptrdiff_t x) {
            if (x < 0 || x >= std::ptrdiff_t(w) || claims[std::size_t(x)] == kUnclaimed) return inf;
            return std::bit_cast<float>(std::uint32_t(claims[std::size_t(x)] >> 32));
        };
        for (std::size_t x = 0; x < w; ++x) {
            const std::ptrdiff_t i = std::ptrdiff_t(x);
            ASSERT_EQ(row_min[x], std::min({at(i - 1), at(i), at(i + 1)})) << "w " << w << " x " << x;
        }
    }
}
