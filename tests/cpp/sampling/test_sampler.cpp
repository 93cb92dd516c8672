// Sampling the virtual texture against independent references: a test-built mip chain
// sampled without indirection (all tiles resident, and fallbacks to ancestors), batched
// against per-sample arithmetic, interleaved and NaN inputs, and closed-form texel values at
// the far end of the widest painting of VT-mobile-VR Table 4.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <random>
#include <tuple>
#include <type_traits>
#include <vector>

#include "common/error.h"
#include "cache/virtual_texture.h"
#include "pack/geometry.h"
#include "pack/tile_key.h"
#include "sampling/mip_texture.h"
#include "sampling/sampler.h"
#include "support/all_tiles.h"

using namespace gigascroll;

namespace {

// Mip chain of a random RGB image by the pack's rule: a texel is the rounded mean of the
// level-0 pixels under it (computed here from level 0 directly, not level by level).
std::vector<MipTexture::Level> make_levels(std::uint32_t W, std::uint32_t H, std::uint32_t count,
                                           std::uint32_t seed) {
    std::mt19937 rng(seed);
    std::vector<MipTexture::Level> levels(count);
    levels[0] = {W, H, std::vector<std::uint8_t>(std::size_t(W) * H * 3)};
    for (auto& b : levels[0].rgb) b = std::uint8_t(rng());
    for (std::uint32_t l = 1; l < count; ++l) {
        auto& lv = levels[l];
        lv.width = (W + (1u << l) - 1) >> l;
        lv.height = (H + (1u << l) - 1) >> l;
        lv.rgb.resize(std::size_t(lv.width) * lv.height * 3);
        for (std::uint32_t y = 0; y < lv.height; ++y)
            for (std::uint32_t x = 0; x < lv.width; ++x)
                for (int c = 0; c < 3; ++c) {
                    std::uint64_t sum = 0, n = 0;
                    for (std::uint32_t yy = y << l; yy < std::min(H, (y + 1) << l); ++yy)
                        for (std::uint32_t xx = x << l; xx < std::min(W, (x + 1) << l); ++xx, ++n)
                            sum += levels[0].rgb[(std::size_t(yy) * W + xx) * 3 + c];
                    lv.rgb[(std::size_t(y) * lv.width + x) * 3 + c] = std::uint8_t((2 * sum + n) / (2 * n));
                }
    }
    return levels;
}

// Cuts tile (tx, ty) of a level with borders clamped to the level's edge, as the pack does.
void cut_tile(const MipTexture::Level& lv, std::uint32_t T, std::uint32_t E, const TileKey& k,
              std::uint8_t* out) {
    const std::int64_t P = T - 2 * E;
    for (std::uint32_t j = 0; j < T; ++j)
        for (std::uint32_t i = 0; i < T; ++i) {
            const std::int64_t x = std::clamp<std::int64_t>(k.tx * P - E + i, 0, lv.width - 1);
            const std::int64_t y = std::clamp<std::int64_t>(k.ty * P - E + j, 0, lv.height - 1);
            for (int c = 0; c < 3; ++c)
                out[(std::size_t(j) * T + i) * 3 + c] = lv.rgb[(std::size_t(y) * lv.width + x) * 3 + c];
        }
}

// A random painting (make_levels) as the pack would cut it, and a cache to fill with its tiles.
struct CutPainting {
    CutPainting(std::uint32_t W, std::uint32_t H, std::uint32_t T, std::uint32_t E, std::uint32_t seed)
        : layout(PackGeometry::make(T, E, {{W, H}})),
          levels(make_levels(W, H, layout.paintings[0].levels(), seed)) {}
    std::uint32_t level_count() const { return layout.paintings[0].levels(); }
    VirtualTexture::TileSource source() const {
        return [this](const TileKey& k, std::uint8_t* out) {
            cut_tile(levels[k.level], layout.tile_size, layout.border, k, out);
        };
    }
    // Inserts the first `count` of `keys`; returns how many inserts evicted a tile.
    std::size_t insert(VirtualTexture& vt, const std::vector<TileKey>& keys, std::size_t count) const {
        std::vector<std::uint8_t> tile(layout.tile_bytes());
        std::size_t evictions = 0;
        for (std::size_t i = 0; i < count; ++i) {
            if (vt.is_resident(keys[i])) continue;
            source()(keys[i], tile.data());
            evictions += vt.insert(keys[i], tile.data()).has_value();
        }
        return evictions;
    }
    // Every tile, or a random share of them in random order.
    std::size_t insert_all(VirtualTexture& vt) const {
        const auto keys = all_tiles(layout);
        return insert(vt, keys, keys.size());
    }
    std::size_t insert_random(VirtualTexture& vt, double share, std::mt19937& rng) const {
        auto keys = all_tiles(layout);
        std::shuffle(keys.begin(), keys.end(), rng);
        return insert(vt, keys, std::size_t(share * keys.size()));
    }
    PackGeometry layout;
    std::vector<MipTexture::Level> levels;
};

}  // namespace

// Samples the VT and the plain mip texture at the same points; returns the max difference.
static float max_difference(const VirtualTexture& vt, const MipTexture& ref, Filter filter,
                            const std::vector<double>& u, const std::vector<double>& v,
                            const std::vector<float>& lod, bool use_answered_level) {
    const std::size_t n = u.size();
    std::vector<float> a(3 * n), b(3 * n);
    std::vector<std::int8_t> answered(n);
    SampleRequest r;
    r.u = u.data();
    r.v = v.data();
    r.lod = lod.data();
    r.count = n;
    r.filter = filter;
    r.out = a.data();
    r.level_out = answered.data();
    r.threads = 2;
    sample(vt, r);
    std::vector<float> lod_ref(lod);
    if (use_answered_level)
        for (std::size_t i = 0; i < n; ++i) lod_ref[i] = answered[i];
    r.lod = lod_ref.data();
    r.out = b.data();
    r.level_out = nullptr;
    ref.sample(r);
    float worst = 0;
    for (std::size_t i = 0; i < 3 * n; ++i) worst = std::max(worst, std::abs(a[i] - b[i]));
    return worst;
}

TEST(VirtualTexture, SamplingEqualsPlainMipTextureWhenResident) {
    const std::uint32_t W = 1001, H = 299;
    const CutPainting painting(W, H, 32, 2, 3);
    const std::uint32_t L = painting.level_count();
    VirtualTexture vt(painting.layout, 24, 24, painting.source());
    ASSERT_EQ(painting.insert_all(vt), 0u) << "the cache must hold every tile here";
    const MipTexture ref(painting.levels);
    std::mt19937 rng(11);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> u, v;
    std::vector<float> lod;
    for (int i = 0; i < 20000; ++i) {
        u.push_back(unit(rng));
        v.push_back(unit(rng));
        lod.push_back(float(unit(rng) * (L - 1)));
    }
    for (double e : {0.0, 1.0, 0.5 / W, 1 - 0.5 / W, 1e-12, 1 - 1e-12})  // edges and corners
        for (double f : {0.0, 1.0, 0.5 / H, 1 - 0.5 / H}) {
            u.push_back(e);
            v.push_back(f);
            lod.push_back(0.0f);
        }
    EXPECT_LT(max_difference(vt, ref, Filter::Bilinear, u, v, lod, false), 1e-3f);
    EXPECT_LT(max_difference(vt, ref, Filter::Trilinear, u, v, lod, false), 1e-3f);
}

TEST(VirtualTexture, MissingTilesFallBackToTheFinestResidentAncestor) {
    const CutPainting painting(777, 333, 32, 3, 5);
    const std::uint32_t L = painting.level_count();
    VirtualTexture vt(painting.layout, 12, 12, painting.source());
    std::mt19937 rng(13);
    painting.insert_random(vt, 0.25, rng);  // a random quarter
    const MipTexture ref(painting.levels);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    std::vector<double> u, v;
    std::vector<float> lod;
    for (int i = 0; i < 20000; ++i) {
        u.push_back(unit(rng));
        v.push_back(unit(rng));
        lod.push_back(std::floor(float(unit(rng) * L)));
    }
    // Bilinear at an integer lod answered by level a == bilinear of the plain level a.
    EXPECT_LT(max_difference(vt, ref, Filter::Bilinear, u, v, lod, true), 1e-3f);
    std::vector<float> a(3 * u.size());
    std::vector<std::int8_t> answered(u.size());
    SampleRequest r;
    r.u = u.data(); r.v = v.data(); r.lod = lod.data(); r.count = u.size();
    r.out = a.data(); r.level_out = answered.data();
    sample(vt, r);
    std::size_t fell_back = 0;
    for (std::size_t i = 0; i < u.size(); ++i) {
        EXPECT_GE(answered[i], lod[i]);
        fell_back += answered[i] > lod[i];
    }
    EXPECT_GT(fell_back, 0u);
}

// The bilinear filter runs batched (taps vectorised, texel reads prefetched); the per-sample
// trilinear reference (sample_trilinear_reference) samples one point at a time with the same
// arithmetic, and at an integer lod it is one bilinear sample. So the two must agree bit for
// bit, fallbacks to ancestors included, whatever the batch and thread boundaries.
TEST(VirtualTexture, BatchedBilinearEqualsPerSampleArithmetic) {
    const CutPainting painting(901, 411, 32, 3, 17);
    const std::uint32_t L = painting.level_count();
    VirtualTexture vt(painting.layout, 14, 14, painting.source());
    std::mt19937 rng(19);
    painting.insert_random(vt, 1.0 / 3, rng);
    std::uniform_real_distribution<double> unit(-0.05, 1.05);  // some outside [0, 1]
    const std::size_t n = 3 * 4096 + 37;  // several parallel chunks, a partial batch
    std::vector<double> u(n), v(n);
    std::vector<float> lod(n);
    for (std::size_t i = 0; i < n; ++i) {
        // Runs of neighbouring points, as a view's pixels are, and some random jumps.
        const bool jump = i % 50 == 0;
        u[i] = jump || i == 0 ? unit(rng) : u[i - 1] + 0.0007;
        v[i] = jump || i == 0 ? unit(rng) : v[i - 1] + 0.0003;
        lod[i] = std::floor(float(unit(rng) * L));  // integer, -1 and L included (clamped)
    }
    auto run = [&](Filter filter, unsigned threads, bool serial, std::vector<float>& out,
                   std::vector<std::int8_t>& answered) {
        out.assign(3 * n, -1.0f);
        answered.assign(n, -1);
        SampleRequest r;
        r.u = u.data(), r.v = v.data(), r.lod = lod.data(), r.count = n, r.filter = filter;
        r.out = out.data(), r.level_out = answered.data(), r.threads = threads;
        serial ? sample_serial(vt, r) : sample(vt, r);
    };
    std::vector<float> ref(3 * n, -1.0f), got;
    std::vector<std::int8_t> ref_level(n, -1), got_level;
    {
        SampleRequest r;
        r.u = u.data(), r.v = v.data(), r.lod = lod.data(), r.count = n;
        r.out = ref.data(), r.level_out = ref_level.data();
        sample_trilinear_reference(vt, r);
    }
    std::size_t fell_back = 0;
    for (std::size_t i = 0; i < n; ++i) fell_back += ref_level[i] > std::clamp(lod[i], 0.0f, float(L - 1));
    EXPECT_GT(fell_back, n / 10) << "the fallback path must be exercised";
    for (unsigned threads : {1u, 2u, 3u}) {
        run(Filter::Bilinear, threads, threads == 1, got, got_level);
        ASSERT_EQ(got_level, ref_level) << threads << " threads";
        for (std::size_t i = 0; i < 3 * n; ++i)
            ASSERT_EQ(got[i], ref[i]) << "value " << i << ", " << threads << " threads";
    }
}

// Trilinear runs batched (on RGB8 slots both levels in one pass, sample_trilinear_rgb8; on
// BC1 as two batched bilinear passes and a blend); it must equal the per-sample
// trilinear reference bit for bit at fractional levels (both levels answered, one of them
// or both by a resident ancestor), at the top level and at NaN, whatever the batch and
// thread boundaries and with interleaved (u, v).
TEST(VirtualTexture, BatchedTrilinearEqualsPerSampleArithmetic) {
    const CutPainting painting(1203, 377, 32, 3, 23);
    const std::uint32_t L = painting.level_count();
    VirtualTexture vt(painting.layout, 14, 14, painting.source());
    std::mt19937 rng(29);
    painting.insert_random(vt, 0.4, rng);
    std::uniform_real_distribution<double> unit(-0.05, 1.05);
    const std::size_t n = 2 * 4096 + 300;
    std::vector<double> uv(2 * n);
    std::vector<float> lod(n);
    for (std::size_t i = 0; i < n; ++i) {
        const bool jump = i % 70 == 0;
        uv[2 * i] = jump || i == 0 ? unit(rng) : uv[2 * i - 2] + 0.0005;
        uv[2 * i + 1] = jump || i == 0 ? unit(rng) : uv[2 * i - 1] + 0.0002;
        lod[i] = float(unit(rng) * (L + 1)) - 0.5f;  // fractional, below 0 and above the top
        if (i % 97 == 0) lod[i] = std::floor(lod[i]);
        if (i % 331 == 0) lod[i] = std::numeric_limits<float>::quiet_NaN();
    }
    auto request = [&](std::vector<float>& out, std::vector<std::int8_t>& answered) {
        out.assign(3 * n, -1.0f);
        answered.assign(n, -1);
        SampleRequest r;
        r.u = uv.data(), r.v = uv.data() + 1, r.uv_stride = 2, r.lod = lod.data(), r.count = n;
        r.filter = Filter::Trilinear, r.out = out.data(), r.level_out = answered.data();
        return r;
    };
    std::vector<float> ref, got;
    std::vector<std::int8_t> ref_level, got_level;
    sample_trilinear_reference(vt, request(ref, ref_level));
    std::size_t blended = 0;
    for (std::size_t i = 0; i < n; ++i) blended += lod[i] > 0 && lod[i] < float(L - 1) && lod[i] != std::floor(lod[i]);
    EXPECT_GT(blended, n / 2);
    for (unsigned threads : {0u, 1u, 2u, 3u}) {
        SampleRequest r = request(got, got_level);
        r.threads = threads;
        threads == 0 ? sample_serial(vt, r) : sample(vt, r);
        ASSERT_EQ(got_level, ref_level) << threads << " threads";
        for (std::size_t i = 0; i < 3 * n; ++i)
            ASSERT_EQ(got[i], ref[i]) << "value " << i << ", " << threads << " threads";
    }
}

// The display pass's calls: dense u and v, one call per run of one painting under a read lock
// the caller holds (sample_serial_locked), runs of every length from 1 up (partial batches,
// whose taps are padded to whole vectors, and whole ones): each run must equal the per-sample
// trilinear reference bit for bit, with half the tiles resident (fallbacks) and with all of
// them (where 16 samples' taps lie in one tile at both levels, the sampler takes the two
// slots' bases once); and with every sample of a run at one level (a whole integer level, a
// magnified painting below level 0, or beyond the coarsest: the sampler reads the fine
// level alone).
class TrilinearRuns : public ::testing::TestWithParam<std::tuple<double, bool>> {};

TEST_P(TrilinearRuns, OfAnyLengthEqualPerSampleArithmetic) {
    const CutPainting painting(777, 1301, 32, 3, 31);
    const std::uint32_t L = painting.level_count();
    VirtualTexture vt(painting.layout, 40, 40, painting.source());
    std::mt19937 rng(37);
    const auto [resident, one_level] = GetParam();
    painting.insert_random(vt, resident, rng);
    std::uniform_real_distribution<double> unit(-0.02, 1.02);
    std::vector<double> u, v;
    std::vector<float> lod;
    std::vector<std::size_t> run_start;
    for (std::size_t len = 1; len <= 150; len += (len < 20 ? 1 : 13)) {
        run_start.push_back(u.size());
        double u0 = unit(rng), v0 = unit(rng);
        const float lod0 = float(unit(rng) * L);
        // One level per run: a whole level, below 0 or beyond the coarsest.
        const float one = std::array<float, 3>{std::round(lod0), -0.4f, float(L) + 0.5f}[len % 3];
        for (std::size_t k = 0; k < len; ++k) {  // a row of pixels across the painting
            u.push_back(u0 + 0.0011 * double(k)), v.push_back(v0 + 0.0002 * double(k));
            lod.push_back(one_level ? one : lod0 + 0.003f * float(k));
        }
    }
    run_start.push_back(u.size());
    const std::size_t n = u.size();
    std::vector<float> ref(3 * n, -1.0f), got(3 * n, -2.0f);
    std::vector<std::int8_t> ref_level(n, -1), got_level(n, -2);
    SampleRequest r;
    r.u = u.data(), r.v = v.data(), r.lod = lod.data(), r.count = n, r.filter = Filter::Trilinear;
    r.out = ref.data(), r.level_out = ref_level.data();
    sample_trilinear_reference(vt, r);
    {
        const auto lock = vt.read_lock();
        for (std::size_t q = 0; q + 1 < run_start.size(); ++q) {
            const std::size_t b = run_start[q], e = run_start[q + 1];
            SampleRequest s = r;
            s.u = u.data() + b, s.v = v.data() + b, s.lod = lod.data() + b, s.count = e - b;
            s.out = got.data() + 3 * b, s.level_out = got_level.data() + b;
            sample_serial_locked(vt, s);
        }
    }
    ASSERT_EQ(got_level, ref_level);
    for (std::size_t i = 0; i < 3 * n; ++i) ASSERT_EQ(got[i], ref[i]) << "value " << i;
}
INSTANTIATE_TEST_SUITE_P(VirtualTexture, TrilinearRuns,
                         ::testing::Combine(::testing::Values(0.5, 1.0), ::testing::Bool()));

// Interleaved (u, v) pairs (the display pass's layout), a scalar lod and NaN inputs: NaN
// coordinates sample at 0 and a NaN lod at level 0, in both filters' code.
TEST(VirtualTexture, InterleavedUvScalarLodAndNanInputs) {
    const CutPainting painting(300, 200, 32, 2, 23);
    VirtualTexture vt(painting.layout, 16, 16, painting.source());
    ASSERT_EQ(painting.insert_all(vt), 0u);
    const MipTexture ref(painting.levels);
    const double nan = std::numeric_limits<double>::quiet_NaN();
    std::mt19937 rng(29);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const std::size_t n = 201;
    std::vector<double> u(n), v(n), uv(2 * n);
    for (std::size_t i = 0; i < n; ++i) {
        u[i] = i % 7 == 0 ? nan : unit(rng);
        v[i] = i % 11 == 0 ? nan : unit(rng);
        uv[2 * i] = u[i], uv[2 * i + 1] = v[i];
    }
    std::vector<double> u_clean(u), v_clean(v);
    for (std::size_t i = 0; i < n; ++i) {
        if (std::isnan(u_clean[i])) u_clean[i] = 0;
        if (std::isnan(v_clean[i])) v_clean[i] = 0;
    }
    for (Filter filter : {Filter::Bilinear, Filter::Trilinear})
        for (float lod_scalar : {0.0f, 1.4f, 2.0f, std::numeric_limits<float>::quiet_NaN()}) {
            auto sample = [&](const auto& texture, const double* pu, const double* pv,
                              std::size_t stride, const float* lod) {
                std::vector<float> out(3 * n);
                SampleRequest r;
                r.u = pu, r.v = pv, r.uv_stride = stride, r.count = n, r.filter = filter;
                r.lod = lod, r.lod_scalar = lod_scalar, r.out = out.data();
                if constexpr (std::is_same_v<std::decay_t<decltype(texture)>, VirtualTexture>)
                    gigascroll::sample(texture, r);
                else
                    texture.sample(r);
                return out;
            };
            const float lod_clean = std::isnan(lod_scalar) ? 0.0f : lod_scalar;
            const std::vector<float> lods(n, lod_clean);
            const auto expect = sample(vt, u_clean.data(), v_clean.data(), 1, lods.data());
            EXPECT_EQ(sample(vt, uv.data(), uv.data() + 1, 2, nullptr), expect);
            EXPECT_EQ(sample(vt, u.data(), v.data(), 1, nullptr), expect);
            EXPECT_EQ(sample(ref, uv.data(), uv.data() + 1, 2, nullptr),
                      sample(ref, u_clean.data(), v_clean.data(), 1, lods.data()));
        }
    // A stride of 0 would read one point over and over: refused by both textures.
    std::vector<float> out(3 * n);
    SampleRequest bad;
    bad.u = u.data(), bad.v = v.data(), bad.uv_stride = 0, bad.count = n, bad.out = out.data();
    EXPECT_THROW(sample(vt, bad), InvalidArgument);
    EXPECT_THROW(sample_serial(vt, bad), InvalidArgument);
    EXPECT_THROW(ref.sample(bad), InvalidArgument);
}

TEST(VirtualTexture, ExactToA256thTexelAtTheFarEndOfTheWidestPainting) {
    // 196301 x 5197 (VT-mobile-VR Table 4). Level 0 alternates 0 / 255 between columns, so a
    // bilinear sample between two texels reads the fraction directly: value = 255 f or 255 (1-f).
    const std::uint32_t W = 196301, H = 5197, T = 128, E = 4, P = T - 2 * E;
    const PackGeometry layout = PackGeometry::make(T, E, {{W, H}});
    auto texel = [&](std::int64_t x) -> std::uint8_t { return (std::clamp<std::int64_t>(x, 0, W - 1) % 2) ? 255 : 0; };
    auto source = [&](const TileKey& k, std::uint8_t* out) {
        for (std::uint32_t j = 0; j < T; ++j)
            for (std::uint32_t i = 0; i < T; ++i)
                for (int c = 0; c < 3; ++c)
                    out[(std::size_t(j) * T + i) * 3 + c] = k.level == 0 ? texel(std::int64_t(k.tx) * P - E + i) : 77;
    };
    VirtualTexture vt(layout, 8, 8, source);
    std::vector<std::uint8_t> tile(layout.tile_bytes());
    const std::uint32_t last = layout.paintings[0].tiles_x(0) - 1;
    for (std::uint32_t tx : {last - 1, last}) {
        source({0, 0, tx, 20}, tile.data());
        vt.insert({0, 0, tx, 20}, tile.data());
    }
    std::vector<double> u, v;
    std::vector<double> expect;
    for (int k = 0; k <= 256; ++k) {  // x0 from texel centre W-3 to W-2 in 1/256 steps
        const double x0 = (W - 3) + 0.5 + k / 256.0;
        u.push_back(x0 / W);
        v.push_back((20 * P + 60.5) / H);
        const double f = k / 256.0;
        expect.push_back(texel(W - 3) * (1 - f) + texel(W - 2) * f);
    }
    std::vector<float> out(3 * u.size()), out32(3 * u.size());
    std::vector<std::int8_t> answered(u.size());
    SampleRequest r;
    r.u = u.data(); r.v = v.data(); r.count = u.size(); r.out = out.data(); r.level_out = answered.data();
    sample(vt, r);
    double worst = 0, worst32 = 0;
    for (std::size_t i = 0; i < u.size(); ++i) {
        ASSERT_EQ(answered[i], 0);
        worst = std::max(worst, std::abs(out[3 * i] - expect[i]));
    }
    // 1/256 texel of a 0-255 ramp is 1 unit; we require a tenth of that.
    EXPECT_LT(worst, 0.1);
    // The same through float32 uv is far off: shows the test can tell.
    std::vector<double> u32(u.size());
    for (std::size_t i = 0; i < u.size(); ++i) u32[i] = double(float(u[i]));
    r.u = u32.data(); r.out = out32.data();
    sample(vt, r);
    for (std::size_t i = 0; i < u.size(); ++i) worst32 = std::max(worst32, std::abs(out32[3 * i] - expect[i]));
    EXPECT_GT(worst32, 1.0);
}

// The display pass's packets: TrilinearLanes::sample16 on 16 neighbouring samples given as
// the display maps them (lane 0's uv in double, the lanes' offsets in float: a row of pixels
// across the painting, at every scale from magnified to minified, sloped rows, rows across
// tile edges, coordinates outside [0, 1], NaN levels, half or all tiles resident) either
// declines or gives the per-sample trilinear reference's samples within 0.01 of a code (the
// same texels and weights to float rounding); with all tiles resident it accepts the packets
// whose footprints lie in one or two tiles per level away from the painting's edges (about
// half of them).
TEST(TrilinearLanes, PacketsFromTheirOriginAgreeWithTheReferenceOrDecline) {
    const CutPainting painting(1777, 901, 64, 4, 41);
    const std::uint32_t L = painting.level_count();
    for (double resident : {1.0, 0.5}) {
        VirtualTexture vt(painting.layout, 24, 24, painting.source());
        std::mt19937 rng(53);
        painting.insert_random(vt, resident, rng);
        TrilinearLanes lanes(vt, 0);
        if (!lanes.enabled()) GTEST_SKIP() << "built without AVX-512: sample16 always declines";
        std::uniform_real_distribution<double> unit(-0.03, 1.03), slope(-1.0, 1.0);
        std::size_t accepted = 0, blended = 0;
        double worst = 0;
        const std::size_t packets = 6000;
        for (std::size_t q = 0; q < packets; ++q) {
            alignas(64) double u[16], v[16];
            alignas(64) float lod[16], r[16], g[16], b[16];
            const double step = std::exp2(slope(rng) * 3.0) / 1777.0;
            const double tilt = q % 5 == 0 ? slope(rng) * 4 : slope(rng) * 0.05;
            const double u0 = unit(rng), v0 = unit(rng);
            const float lod0 = q % 7 == 0 ? float(slope(rng) * L) : float(std::log2(step * 1777.0) + 0.2 * slope(rng));
            PacketUv packet;
            packet.u0 = u0, packet.v0 = v0;
            for (int k = 0; k < 16; ++k) {
                u[k] = u0 + step * k, v[k] = v0 + tilt * step * k;
                lod[k] = lod0 + 0.01f * float(k);
                if (q % 11 == 0) lod[k] = std::floor(lod0);  // one level
                packet.du[k] = float(step * k), packet.dv[k] = float(tilt * step * k), packet.lod[k] = lod[k];
            }
            if (q % 13 == 0) lod[q % 16] = packet.lod[q % 16] = std::numeric_limits<float>::quiet_NaN();
            std::vector<float> ref(48);
            SampleRequest s;
            s.u = u, s.v = v, s.lod = lod, s.count = 16, s.filter = Filter::Trilinear, s.out = ref.data();
            sample_trilinear_reference(vt, s);
            bool ok;
            {
                const auto lock = vt.read_lock();
                ok = lanes.sample16(packet, r, g, b);
            }
            if (!ok) continue;
            ++accepted;
            for (int k = 0; k < 16; ++k) {
                blended += lod[k] > 0 && lod[k] < float(L - 1) && lod[k] != std::floor(lod[k]);
                const float got[3] = {r[k], g[k], b[k]};
                for (int c = 0; c < 3; ++c) {
                    worst = std::max(worst, double(std::abs(got[c] - ref[3 * k + c])));
                    ASSERT_NEAR(got[c], ref[3 * k + c], 0.01) << "packet " << q << " lane " << k;
                }
            }
        }
        EXPECT_GT(blended, 16 * accepted / 8);  // two levels blended in a good share of lanes
        // All resident: about half the packets are accepted (the others reach the painting's
        // edges, span levels more than one apart or three tiles); half resident: fallbacks
        // decline.
        if (resident == 1.0) EXPECT_GT(accepted, packets * 4 / 10);
        else EXPECT_LT(accepted, packets * 9 / 10);
        RecordProperty("largest_difference_codes_" + std::to_string(int(resident * 100)), std::to_string(worst));
    }
}

// sample16 at every width the host has (TrilinearLanes::sample_lanes: W = 1, 8, 16 lanes a
// step, without the common packet's byte-permuted stretches) and with the stretches (AVX-512
// VBMI) against W = 1: the same packets accepted, the same bits (the display's packets as
// above, all tiles or half of them resident).
TEST(TrilinearLanes, EveryWidthAndTheStretchesGiveTheScalarSamples) {
    const CutPainting painting(1777, 901, 64, 4, 41);
    const std::uint32_t L = painting.level_count();
    std::size_t accepted = 0;
    for (double resident : {1.0, 0.5}) {
        VirtualTexture vt(painting.layout, 24, 24, painting.source());
        std::mt19937 rng(59);
        painting.insert_random(vt, resident, rng);
        TrilinearLanes one(vt, 0), wide(vt, 0);
        std::uniform_real_distribution<double> unit(-0.03, 1.03), slope(-1.0, 1.0);
        const auto lock = vt.read_lock();
        for (std::size_t q = 0; q < 3000; ++q) {
            const double step = std::exp2(slope(rng) * 3.0) / 1777.0;
            const double tilt = q % 5 == 0 ? slope(rng) * 4 : slope(rng) * 0.05;
            const float lod0 = q % 7 == 0 ? float(slope(rng) * L) : float(std::log2(step * 1777.0) + 0.2 * slope(rng));
            PacketUv packet;
            packet.u0 = unit(rng), packet.v0 = unit(rng);
            for (int k = 0; k < 16; ++k) {
                packet.du[k] = float(step * k), packet.dv[k] = float(tilt * step * k);
                packet.lod[k] = q % 11 == 0 ? std::floor(lod0) : lod0 + 0.01f * float(k);
            }
            if (q % 13 == 0) packet.lod[q % 16] = std::numeric_limits<float>::quiet_NaN();
            alignas(64) float want[3][16], got[3][16];
            const bool ok = one.sample_lanes<1>(packet, want[0], want[1], want[2], false);
            accepted += ok;
            auto expect_same = [&](bool ok_w, int width, bool stretches) {
                ASSERT_EQ(ok_w, ok) << "width " << width << " stretches " << stretches << " packet " << q;
                if (ok)
                    for (int c = 0; c < 3; ++c)
                        for (int k = 0; k < 16; ++k)
                            ASSERT_EQ(std::bit_cast<std::uint32_t>(got[c][k]), std::bit_cast<std::uint32_t>(want[c][k]))
                                << "width " << width << " stretches " << stretches << " packet " << q << " lane " << k;
            };
#if defined(__AVX2__)
            expect_same(wide.sample_lanes<8>(packet, got[0], got[1], got[2], false), 8, false);
#endif
#if defined(__AVX512F__)
            expect_same(wide.sample_lanes<16>(packet, got[0], got[1], got[2], false), 16, false);
            expect_same(wide.sample_lanes<16>(packet, got[0], got[1], got[2], true), 16, true);
#endif
        }
    }
    EXPECT_GT(accepted, 2000u);  // the packets compared are many
}

// A packet whose lanes reach the painting's edge, where sample() clamps, is declined.
TEST(TrilinearLanes, PacketsFromTheirOriginDeclineAtTheEdges) {
    const CutPainting painting(600, 400, 32, 2, 29);
    VirtualTexture vt(painting.layout, 64, 64, painting.source());
    painting.insert_all(vt);
    TrilinearLanes lanes(vt, 0);
    if (!lanes.enabled()) GTEST_SKIP() << "built without AVX-512: sample16 always declines";
    alignas(64) float r[16], g[16], b[16];
    const auto lock = vt.read_lock();
    for (double u0 : {0.0, 0.5 / 600, 1.0 - 16.0 / 600, 0.4}) {
        PacketUv packet;
        packet.u0 = u0, packet.v0 = 0.5;
        for (int k = 0; k < 16; ++k) packet.du[k] = float(k / 600.0), packet.lod[k] = 0.25f;
        EXPECT_EQ(lanes.sample16(packet, r, g, b), u0 == 0.4) << "u0 " << u0;
    }
    PacketUv nan;
    nan.u0 = 0.5, nan.v0 = 0.5;
    nan.du[3] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_FALSE(lanes.sample16(nan, r, g, b));
    nan.du[3] = 0, nan.v0 = std::numeric_limits<double>::quiet_NaN();
    EXPECT_FALSE(lanes.sample16(nan, r, g, b));
}

// The reference sampler's 16 samples (r, g, b per sample) of a packet's uv and levels.
static std::vector<float> packet_reference(const VirtualTexture& vt, const double* u, const double* v, const float* lod) {
    std::vector<float> out(48);
    SampleRequest s;
    s.u = u, s.v = v, s.lod = lod, s.count = 16, s.filter = Filter::Trilinear, s.out = out.data();
    sample_trilinear_reference(vt, s);
    return out;
}

// A packet across a tile's edge, running right or left (a painting seen mirrored), at one and
// two levels: sampled from both tiles and equal to the reference, both from the tiles' cache
// (the second call) and after forget_tiles; declined while the neighbour tile is not resident
// (the reference falls back to a coarser level for its lanes).
TEST(TrilinearLanes, PacketsAcrossATileEdgeTakeBothTiles) {
    const CutPainting painting(600, 400, 32, 2, 61);
    const std::uint32_t P = painting.layout.payload();
    for (const double direction : {1.0, -1.0})
        for (const float lod0 : {0.0f, 0.4f}) {
            VirtualTexture vt(painting.layout, 16, 16, painting.source());
            std::vector<std::uint8_t> tile(painting.layout.tile_bytes());
            auto put = [&](std::uint32_t l, std::uint32_t tx, std::uint32_t ty) {
                const TileKey key{0, l, tx, ty};
                painting.source()(key, tile.data());
                vt.insert(key, tile.data());
            };
            TrilinearLanes lanes(vt, 0);
            if (!lanes.enabled()) GTEST_SKIP() << "built without AVX-512: sample16 always declines";
            // 16 lanes 0.9 texels apart across the edge between level 0's tiles 4 and 5 (their
            // parents at level 1 are tiles 2 and 2: one tile there), lane 0 on its side.
            alignas(64) double u[16], v[16];
            alignas(64) float lod[16], r[16], g[16], b[16];
            PacketUv packet;
            const double x0 = 5.0 * P - direction * 6.2;
            for (int k = 0; k < 16; ++k) {
                u[k] = (x0 + direction * 0.9 * k) / 600.0, v[k] = (4.5 * P) / 400.0, lod[k] = lod0;
                packet.du[k] = float(u[k] - u[0]), packet.lod[k] = lod0;
            }
            packet.u0 = u[0], packet.v0 = v[0];
            put(0, direction > 0 ? 4 : 5, 4), put(1, 2, 2);
            auto sample = [&] {
                const auto lock = vt.read_lock();
                return lanes.sample16(packet, r, g, b);
            };
            EXPECT_FALSE(sample()) << "direction " << direction << " lod " << lod0;  // one tile resident
            put(0, direction > 0 ? 5 : 4, 4);
            lanes.forget_tiles();
            const std::vector<float> ref = packet_reference(vt, u, v, lod);
            for (int call = 0; call < 2; ++call) {
                ASSERT_TRUE(sample()) << "direction " << direction << " lod " << lod0 << " call " << call;
                for (int k = 0; k < 16; ++k) {
                    EXPECT_NEAR(r[k], ref[3 * k], 0.01f) << "lane " << k;
                    EXPECT_NEAR(g[k], ref[3 * k + 1], 0.01f) << "lane " << k;
                    EXPECT_NEAR(b[k], ref[3 * k + 2], 0.01f) << "lane " << k;
                }
            }
        }
}

// Nothing to sample in lanes for a painting the texture does not hold: sample() reports it.
TEST(TrilinearLanes, DisabledForAPaintingNotInTheTexture) {
    const CutPainting painting(300, 200, 32, 2, 23);
    VirtualTexture vt(painting.layout, 16, 16, painting.source());
    TrilinearLanes lanes(vt, 1);
    EXPECT_FALSE(lanes.enabled());
    PacketUv packet;
    packet.u0 = packet.v0 = 0.5;
    alignas(64) float out[3][16];
    EXPECT_FALSE(lanes.sample16(packet, out[0], out[1], out[2]));
}

// The page entries sample16 keeps between calls are only as current as the caller's read
// lock: after the packet's tiles are evicted (their slots now hold other tiles) and
// forget_tiles(), it declines (the tiles fell back to an ancestor) or equals the reference
// again, never the evicted tiles' texels.
TEST(TrilinearLanes, ForgetsItsTilesWhenTheResidencyChanges) {
    const CutPainting painting(600, 400, 32, 2, 47);
    VirtualTexture vt(painting.layout, 8, 8, painting.source());
    TrilinearLanes lanes(vt, 0);
    if (!lanes.enabled()) GTEST_SKIP() << "built without AVX-512: sample16 always declines";
    const std::uint32_t P = painting.layout.payload();
    // A magnified packet in the middle of level 0's tile (5, 4) and level 1's (2, 2).
    alignas(64) double u[16], v[16];
    alignas(64) float lod[16], r[16], g[16], b[16];
    PacketUv packet;
    for (int k = 0; k < 16; ++k) {
        u[k] = (5.3 * P + 0.2 * k) / 600.0, v[k] = (4.5 * P) / 400.0, lod[k] = 0.4f;
        packet.du[k] = float(u[k] - u[0]), packet.lod[k] = lod[k];
    }
    packet.u0 = u[0], packet.v0 = v[0];
    std::vector<std::uint8_t> tile(painting.layout.tile_bytes());
    auto put = [&](std::uint32_t l, std::uint32_t tx, std::uint32_t ty) {
        const TileKey k{0, l, tx, ty};
        painting.source()(k, tile.data());
        vt.insert(k, tile.data());
    };
    put(0, 5, 4), put(1, 2, 2);
    auto reference = [&] { return packet_reference(vt, u, v, lod); };
    auto lanes_equal = [&](const std::vector<float>& ref) {  // to the packets' 0.01 of a code
        for (int k = 0; k < 16; ++k)
            if (std::abs(r[k] - ref[3 * k]) > 0.01f || std::abs(g[k] - ref[3 * k + 1]) > 0.01f ||
                std::abs(b[k] - ref[3 * k + 2]) > 0.01f)
                return false;
        return true;
    };
    const std::vector<float> before = reference();
    {
        const auto lock = vt.read_lock();
        ASSERT_TRUE(lanes.sample16(packet, r, g, b));
    }
    EXPECT_TRUE(lanes_equal(before));
    // Every other level-0 tile of the painting's first rows: the cache's least recently used
    // slots go first, the packet's two tiles among them.
    for (std::uint32_t ty = 0; ty < 3; ++ty)
        for (std::uint32_t tx = 0; tx < 22; ++tx) put(0, tx, ty);
    ASSERT_FALSE(vt.is_resident(TileKey{0, 0, 5, 4}));
    ASSERT_FALSE(vt.is_resident(TileKey{0, 1, 2, 2}));
    const std::vector<float> after = reference();
    ASSERT_NE(after, before);  // a coarser ancestor answers now
    lanes.forget_tiles();
    bool ok;
    {
        const auto lock = vt.read_lock();
        ok = lanes.sample16(packet, r, g, b);
    }
    if (ok) EXPECT_TRUE(lanes_equal(after));
}
