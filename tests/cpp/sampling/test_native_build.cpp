// The core is compiled for the building machine's CPU (GIGASCROLL_NATIVE, wide vectors) in
// `make test` and for baseline x86-64 in `make sanitize`. Floating-point contraction is off
// in both, so the vectorised loops must give the same floats as the scalar ones: this test
// digests the feedback pass's and the sampler's outputs on fixed inputs and compares them
// with constants that both builds must reproduce. A deliberate change to that arithmetic
// changes the constants; the failure message prints the new ones.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "common/checksum.h"
#include "views/exhibition.h"
#include "pack/tile_key.h"
#include "cache/virtual_texture.h"
#include "sampling/sampler.h"
#include "support/feedback_image.h"

using namespace gigascroll;

namespace {

template <typename T>
std::uint64_t digest(const std::vector<T>& v) {
    return checksum64(v.data(), v.size() * sizeof(T));
}

}  // namespace

TEST(BuildResults, FeedbackPassGivesTheSameFloatsInEveryBuild) {
    // The view lies inside the painting (seen at an angle, so levels vary), away from its
    // edges: which surface a ray hits does not then depend on the ray tracer's kernel.
    const PaintingOnWall wall(PaintingGeometry(20000, 14000));
    const Camera cam({0.4, 0.7, -0.5}, {0.3, -0.1, 1}, {0, 1, 0}, 0.3, 0.3, 1600, 1600);
    const auto [keys, lod, uv] = feedback_image(wall.scene, cam, 200, 200);
    std::set<std::uint32_t> levels;
    for (std::uint64_t k : keys) {
        ASSERT_NE(k, kNoRequest);
        levels.insert(request_level(k));
    }
    EXPECT_GE(levels.size(), 2u);
    EXPECT_EQ(digest(keys), 0x71960a302e7c562cull) << std::hex << "keys 0x" << digest(keys);
    EXPECT_EQ(digest(lod), 0x9893c47ad83b964cull) << std::hex << "lod 0x" << digest(lod);
    EXPECT_EQ(digest(uv), 0x2cca77a7e303393bull) << std::hex << "uv 0x" << digest(uv);
}

TEST(BuildResults, SamplingGivesTheSameFloatsInEveryBuild) {
    const PackGeometry layout = PackGeometry::make(32, 2, {{500, 300}});
    // Tile content from its key and texel index alone.
    auto source = [](const TileKey& k, std::uint8_t* out) {
        std::mt19937 rng(std::uint32_t(k.packed() * 2654435761u));
        for (std::size_t i = 0; i < 32 * 32 * 3; ++i) out[i] = std::uint8_t(rng());
    };
    VirtualTexture vt(layout, 20, 20, source);
    std::vector<std::uint8_t> tile(layout.tile_bytes());
    const PaintingGeometry& p = layout.paintings[0];
    for (std::uint32_t l = 0; l < p.levels(); l += 2)  // every other level: fallbacks too
        for (std::uint32_t y = 0; y < p.tiles_y(l); ++y)
            for (std::uint32_t x = 0; x < p.tiles_x(l); ++x) {
                source({0, l, x, y}, tile.data());
                vt.insert({0, l, x, y}, tile.data());
            }
    std::mt19937 rng(5);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const std::size_t n = 5000;
    std::vector<double> u(n), v(n);
    std::vector<float> lod(n);
    for (std::size_t i = 0; i < n; ++i)
        u[i] = unit(rng), v[i] = unit(rng), lod[i] = float(unit(rng) * p.levels());
    for (Filter filter : {Filter::Bilinear, Filter::Trilinear}) {
        std::vector<float> out(3 * n);
        SampleRequest r;
        r.u = u.data(), r.v = v.data(), r.lod = lod.data(), r.count = n, r.filter = filter;
        r.out = out.data();
        sample(vt, r);
        const std::uint64_t expect = filter == Filter::Bilinear ? 0xdd6fa3c267c74237ull : 0xbfba62f8cb88f6a4ull;
        EXPECT_EQ(digest(out), expect) << std::hex << "filter " << int(filter) << ": 0x" << digest(out);
    }
}
