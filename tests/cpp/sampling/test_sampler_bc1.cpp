// Sampling BC1 slots, which decode the footprint's texels on the fly, against two references:
// an RGB8 cache holding the same tiles decoded whole (the same floats, bit for bit, with
// fallbacks to ancestors), and the plain mip chain stitched from the decoded tiles' payloads,
// which only matches at tile seams if neighbouring tiles' borders decode alike.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <vector>

#include "cache/virtual_texture.h"
#include "pack/reader.h"
#include "pack/temp_pack.h"
#include "sampling/mip_texture.h"
#include "sampling/sampler.h"
#include "support/all_tiles.h"

using namespace gigascroll;

namespace {

struct Bc1Fixture {
    static constexpr std::uint32_t W = 611, H = 233, T = 32, E = 4;
    TempDir dir;
    std::unique_ptr<TilePack> pack;
    Bc1Fixture() {
        std::mt19937 rng(5);
        std::vector<std::uint8_t> img(std::size_t(W) * H * 3);
        for (std::uint32_t y = 0; y < H; ++y)
            for (std::uint32_t x = 0; x < W; ++x)
                for (int c = 0; c < 3; ++c)
                    img[(std::size_t(y) * W + x) * 3 + c] = std::uint8_t(
                        std::clamp(int(128 + 90 * std::sin(0.07 * x + 0.04 * y * (c + 1))) + int(rng() % 31) - 15, 0, 255));
        build(dir.path, img, W, H, T, E, Codec::Bc1, 64, 2);
        pack = std::make_unique<TilePack>(dir.path.string());
    }
    // A cache of bc1 slots (blocks as stored) or of RGB8 slots (the same tiles decoded).
    VirtualTexture cache(TexelFormat f, std::uint32_t slots) const {
        const TilePack& p = *pack;
        auto source = [&p, f](const TileKey& k, std::uint8_t* out) {
            if (f == TexelFormat::Bc1) p.read_slot_tile(k.painting, k.level, k.tx, k.ty, out);
            else p.read_tile(k.painting, k.level, k.tx, k.ty, out);
        };
        return VirtualTexture(p.geometry(), slots, slots, source, f);
    }
    void insert(VirtualTexture& vt, const std::vector<TileKey>& keys) const {
        std::vector<std::uint8_t> tile(vt.slot_bytes());
        for (const TileKey& k : keys) {
            if (vt.format() == TexelFormat::Bc1) pack->read_slot_tile(k.painting, k.level, k.tx, k.ty, tile.data());
            else pack->read_tile(k.painting, k.level, k.tx, k.ty, tile.data());
            vt.insert(k, tile.data());
        }
    }
};

std::vector<float> run(const VirtualTexture& vt, Filter f, const std::vector<double>& u,
                       const std::vector<double>& v, const std::vector<float>& lod,
                       std::vector<std::int8_t>* answered = nullptr) {
    std::vector<float> out(3 * u.size());
    SampleRequest r;
    r.u = u.data(), r.v = v.data(), r.lod = lod.data(), r.count = u.size();
    r.filter = f, r.out = out.data(), r.threads = 2;
    if (answered) answered->resize(u.size()), r.level_out = answered->data();
    sample(vt, r);
    return out;
}

}  // namespace

TEST(SamplerBc1, EqualsRgb8CacheOfTheDecodedTilesBitForBit) {
    const Bc1Fixture fx;
    VirtualTexture bc1 = fx.cache(TexelFormat::Bc1, 10), rgb = fx.cache(TexelFormat::Rgb8, 10);
    EXPECT_EQ(rgb.slot_bytes(), 6 * bc1.slot_bytes());
    auto keys = all_tiles(fx.pack->geometry());
    std::mt19937 rng(3);
    std::shuffle(keys.begin(), keys.end(), rng);
    keys.resize(keys.size() / 3);  // partly resident: fallbacks to ancestors too
    fx.insert(bc1, keys);
    fx.insert(rgb, keys);
    const std::uint32_t L = fx.pack->paintings()[0].geometry.levels();
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> u, v;
    std::vector<float> lod;
    for (int i = 0; i < 30000; ++i) {
        u.push_back(unit(rng)), v.push_back(unit(rng));
        lod.push_back(float(unit(rng) * (L - 1)));
    }
    for (Filter f : {Filter::Bilinear, Filter::Trilinear}) {
        std::vector<std::int8_t> la, lb;
        const auto a = run(bc1, f, u, v, lod, &la), b = run(rgb, f, u, v, lod, &lb);
        ASSERT_EQ(0, std::memcmp(a.data(), b.data(), a.size() * sizeof(float)));
        ASSERT_EQ(la, lb);
    }
}

// Samples straddling tile seams (positions within a texel of k P at every level) equal the
// stitched mip chain of the decoded payloads: the border texels a footprint reads from one
// tile are the ones its neighbour holds.
TEST(SamplerBc1, SeamlessAcrossTilesUnderBilinear) {
    const Bc1Fixture fx;
    VirtualTexture bc1 = fx.cache(TexelFormat::Bc1, 20);  // every tile resident
    fx.insert(bc1, all_tiles(fx.pack->geometry()));
    const MipTexture ref = MipTexture::from_pack(*fx.pack, 0);
    const std::uint32_t P = Bc1Fixture::T - 2 * Bc1Fixture::E;
    std::mt19937 rng(9);
    std::uniform_real_distribution<double> unit(0.0, 1.0), near(-1.0, 1.0);
    std::vector<double> u, v;
    std::vector<float> lod;
    for (std::uint32_t l = 0; l < ref.level_count(); ++l) {
        const double scale = double(1u << l);
        for (int i = 0; i < 4000; ++i) {
            const std::uint32_t wl = ref.level(l).width, hl = ref.level(l).height;
            const double sx = P * std::floor(unit(rng) * std::max(1u, wl / P)) + near(rng);
            const double sy = P * std::floor(unit(rng) * std::max(1u, hl / P)) + near(rng);
            u.push_back(std::clamp(sx * scale / Bc1Fixture::W, 0.0, 1.0));
            v.push_back(i % 2 ? std::clamp(sy * scale / Bc1Fixture::H, 0.0, 1.0) : unit(rng));
            lod.push_back(float(l));
        }
    }
    const auto a = run(bc1, Filter::Bilinear, u, v, lod);
    std::vector<float> b(a.size());
    SampleRequest r;
    r.u = u.data(), r.v = v.data(), r.lod = lod.data(), r.count = u.size(), r.out = b.data();
    ref.sample(r);
    float worst = 0;
    for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
    EXPECT_LT(worst, 1e-3f);
}
