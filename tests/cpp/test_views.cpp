// Views subsystem: tile geometry, request keys, the feedback pass against analytic
// footprints, and the four request-processing methods against a brute-force reference.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "common/error.h"
#include "feedback_image.h"
#include "views/exhibition.h"
#include "views/feedback.h"
#include "pack/tile_key.h"
#include "views/request_hash.h"
#include "views/request_processing.h"
#include "views/residency.h"

using namespace gigascroll;

namespace {

std::vector<std::uint64_t> sorted(std::vector<std::uint64_t> v) {
    std::sort(v.begin(), v.end());
    return v;
}

// Brute force: the distinct non-empty keys of the buffers.
std::set<std::uint64_t> distinct(const std::vector<std::vector<std::uint64_t>>& buffers) {
    std::set<std::uint64_t> s;
    for (const auto& b : buffers)
        for (auto k : b)
            if (k != kNoRequest) s.insert(k);
    return s;
}

std::vector<FeedbackBuffer> spans(const std::vector<std::vector<std::uint64_t>>& buffers) {
    return {buffers.begin(), buffers.end()};
}

// Random feedback: runs of equal keys (as neighbouring pixels give) and empty pixels.
std::vector<std::vector<std::uint64_t>> random_buffers(const std::vector<PaintingGeometry>& paintings,
                                                       std::size_t count, std::size_t pixels,
                                                       std::size_t distinct_keys, unsigned seed) {
    std::mt19937_64 rng(seed);
    std::vector<std::uint64_t> pool;
    for (std::size_t i = 0; i < distinct_keys; ++i) {
        const auto p = std::uint32_t(rng() % paintings.size());
        const auto l = std::uint32_t(rng() % paintings[p].levels());
        pool.push_back(pack_request(p, l, std::uint32_t(rng() % paintings[p].tiles_x(l)),
                                    std::uint32_t(rng() % paintings[p].tiles_y(l))));
    }
    std::vector<std::vector<std::uint64_t>> out(count);
    for (auto& b : out) {
        while (b.size() < pixels) {
            const std::uint64_t k = rng() % 7 == 0 ? kNoRequest : pool[rng() % pool.size()];
            b.insert(b.end(), std::min<std::size_t>(1 + rng() % 9, pixels - b.size()), k);
        }
    }
    return out;
}

std::vector<PaintingGeometry> small_paintings() {
    return {PaintingGeometry(5000, 700), PaintingGeometry(1200, 3000), PaintingGeometry(800, 800, 64, 2)};
}

ResidentSet random_residency(const std::vector<PaintingGeometry>& paintings, unsigned seed) {
    ResidentSet r(paintings);
    std::mt19937_64 rng(seed);
    for (std::uint32_t p = 0; p < paintings.size(); ++p)
        for (std::uint32_t l = 0; l < paintings[p].levels(); ++l)
            for (std::uint32_t y = 0; y < paintings[p].tiles_y(l); ++y)
                for (std::uint32_t x = 0; x < paintings[p].tiles_x(l); ++x)
                    if (rng() % 3 == 0) r.insert(pack_request(p, l, x, y));
    return r;
}

}  // namespace

TEST(PaintingGeometry, ScrollPyramidMatchesDirectCount) {
    const PaintingGeometry t(152089, 6083);  // the seed's scroll, 128-texel tiles, 4-texel border
    EXPECT_EQ(t.payload(), 120u);
    // Direct count: halve (rounding up) until one 120-texel tile holds the level.
    std::uint64_t w = 152089, h = 6083, total = 0;
    std::uint32_t levels = 0;
    for (;;) {
        const std::uint64_t tx = (w + 119) / 120, ty = (h + 119) / 120;
        EXPECT_EQ(t.tiles_x(levels), tx);
        EXPECT_EQ(t.tiles_y(levels), ty);
        total += tx * ty;
        ++levels;
        if (tx == 1 && ty == 1) break;
        w = (w + 1) / 2, h = (h + 1) / 2;
    }
    EXPECT_EQ(t.levels(), levels);
    EXPECT_EQ(t.levels(), 12u);
    EXPECT_EQ(t.total_tiles(), total);
    EXPECT_EQ(t.page_table_width(), 2048u);  // 1268 tiles -> 2048
    EXPECT_EQ(t.page_table_height(), 64u);   // 51 tiles -> 64
    EXPECT_THROW(PaintingGeometry(0, 10), InvalidArgument);
    EXPECT_THROW(PaintingGeometry(10, 10, 8, 4), InvalidArgument);
}

TEST(RequestKey, RoundTripBeyondSeedFieldWidths) {
    // More than 16 paintings, 16 levels and 4096 tiles per axis must not overflow.
    const Request cases[] = {{0, 0, 0, 0}, {17, 20, 4097, 65535}, {kMaxPaintings - 1, 31, 65535, 1},
                             {40, 11, 1267, 50}};
    for (const Request& r : cases) {
        if (r.painting == kMaxPaintings - 1 && r.level == 31) continue;
        EXPECT_EQ(unpack_request(pack_request(r)), r);
    }
    EXPECT_NE(pack_request(17, 1, 0, 0), pack_request(1, 17, 0, 0));
    // Morton against bit-by-bit interleaving.
    std::mt19937 rng(1);
    for (int i = 0; i < 1000; ++i) {
        const std::uint32_t x = rng() & 0xFFFF, y = rng() & 0xFFFF;
        std::uint32_t m = 0;
        for (int b = 0; b < 16; ++b) m |= ((x >> b) & 1u) << (2 * b) | ((y >> b) & 1u) << (2 * b + 1);
        EXPECT_EQ(morton2(x, y), m);
    }
    EXPECT_EQ(ancestor_request(pack_request(3, 2, 13, 6), 4), pack_request(3, 4, 3, 1));
}

TEST(TileIndex, IsABijectionOverEveryTile) {
    const TileIndex index(small_paintings());
    std::uint64_t expect = 0;
    for (const auto& p : small_paintings()) expect += p.total_tiles();
    ASSERT_EQ(index.size(), expect);
    for (std::uint64_t i = 0; i < index.size(); ++i) ASSERT_EQ(index.index(index.key(i)), i);
    EXPECT_THROW(index.index(pack_request(3, 0, 0, 0)), InvalidArgument);
    EXPECT_THROW(index.index(pack_request(0, 0, 9999, 0)), InvalidArgument);
}

TEST(ResidentSet, FinestResidentAncestor) {
    ResidentSet r({PaintingGeometry(1000, 1000)});  // levels: 9x9, 5x5, 3x3, 2x2, 1x1
    ASSERT_EQ(r.paintings()[0].levels(), 5u);
    const std::uint64_t q = pack_request(0, 0, 7, 8);
    EXPECT_EQ(r.resident_level(q), 4u);  // only the coarsest tile
    r.insert(pack_request(0, 2, 1, 2));
    EXPECT_EQ(r.resident_level(q), 2u);
    r.insert(pack_request(0, 0, 7, 8));
    EXPECT_EQ(r.resident_level(q), 0u);
    EXPECT_EQ(response_of(r, pack_request(0, 1, 3, 4)), pack_request(0, 2, 1, 2));
    EXPECT_THROW(r.resident_level(pack_request(1, 0, 0, 0)), InvalidArgument);
}

namespace {
// A wall painting facing -z with texel (0,0) at (0, 1, 0), like the scroll.
struct WallScene {
    ExhibitionScene scene;
    PaintingGeometry tiles{152089, 6083};
    WallScene() {
        scene.add_painting(0, tiles, {0, 1.75, 0}, {1, 0, 0}, {0, -1, 0}, 12.0, 0.5);
        scene.add_box({-1, 0, 0.01}, {13, 3, 0.2});
        scene.commit();
    }
};
const double kTexel = 12.0 / 152089;
const double kTanHalf = 900 * kTexel / 0.072;  // the Quest Pro assumption of views.py
}  // namespace

TEST(Feedback, HeadOnLevelMatchesAnalyticFootprint) {
    WallScene w;
    for (double d : {0.05, 0.072, 0.1, 0.25, 0.4, 1.0, 3.0}) {
        const Camera cam({6, 1.5, -d}, {0, 0, 1}, {0, 1, 0}, kTanHalf, kTanHalf * 1920 / 1800, 1800,
                         1920);
        // Analytic: a display pixel spans 2 tan(fov/2) / W radians on the axis, d times that
        // in metres, over the texel size; head-on the footprint is the same everywhere.
        const double rho = d * 2 * kTanHalf / 1800 / kTexel;
        FeedbackOptions o{45, 48, 0, 2};
        std::vector<std::uint64_t> keys(45 * 48);
        std::vector<float> lod(keys.size());
        render_feedback(w.scene, cam, o, keys.data(), lod.data());
        int seen = 0;
        for (std::size_t i = 0; i < keys.size(); ++i) {
            if (keys[i] == kNoRequest) continue;
            ++seen;
            EXPECT_NEAR(lod[i], std::log2(rho), 1e-4) << "d=" << d;
            const std::uint32_t expect = rho <= 1 ? 0 : std::uint32_t(std::floor(std::log2(rho)));
            EXPECT_EQ(request_level(keys[i]), std::min(expect, 11u)) << "d=" << d;
        }
        EXPECT_GT(seen, 0);
    }
    // The seed's set-up: 40 cm asks level 2, 25 cm level 1; level 0 (rho <= 1) at 7.2 cm.
    EXPECT_EQ(std::floor(std::log2(0.4 * 2 * kTanHalf / 1800 / kTexel)), 2);
    EXPECT_EQ(std::floor(std::log2(0.25 * 2 * kTanHalf / 1800 / kTexel)), 1);
}

TEST(Feedback, GrazingLevelMatchesAnalyticFootprint) {
    WallScene w;
    const double d = 0.5;  // perpendicular distance to the wall
    for (double deg : {0.0, 30.0, 60.0, 75.0, 85.0}) {
        const double th = deg * M_PI / 180;
        // Looking at (6, 1.5, 0) from a point rotated by th about the vertical.
        const Vec3d target{6, 1.5, 0}, pos{6 - d * std::tan(th), 1.5, -d};
        const Camera cam(pos, target - pos, {0, 1, 0}, kTanHalf, kTanHalf, 1800, 1800);
        // Centre pixel: the ray travels t = d / cos th; a pixel step along the tilt stretches
        // by 1 / cos th on the wall, the vertical step does not.
        const double pitch = 2 * kTanHalf / 1800, t = d / std::cos(th);
        const double rho = std::max(t * pitch / std::cos(th), t * pitch) / kTexel;
        const std::uint32_t W = 61;  // odd: the middle feedback pixel is the display centre
        FeedbackOptions o{W, W, 0, 2};
        std::vector<std::uint64_t> keys(W * W);
        std::vector<float> lod(keys.size());
        render_feedback(w.scene, cam, o, keys.data(), lod.data());
        const std::size_t centre = (W / 2) * W + W / 2;
        ASSERT_NE(keys[centre], kNoRequest);
        EXPECT_NEAR(lod[centre], std::log2(rho), 1e-4) << deg;
        EXPECT_EQ(request_level(keys[centre]), mip_level(std::log2(rho), 12)) << deg;
        EXPECT_NEAR(texel_footprint(w.scene.paintings()[0], cam, cam.direction(900, 900), t), rho,
                    1e-9 * rho);
        // The tile holds the texel the centre ray hits: x = 6 m.
        const Request r = unpack_request(keys[centre]);
        EXPECT_EQ(r.x, std::uint32_t(6.0 / kTexel / (120.0 * (1 << r.level))));
    }
}

TEST(Feedback, LodBiasAndDisplayGrid) {
    WallScene w;
    const double d = 0.4;
    const Camera cam({6, 1.5, -d}, {0.1, 0.05, 1}, {0, 1, 0}, kTanHalf, kTanHalf * 1920 / 1800,
                     1800, 1920);
    const std::uint32_t W = 45, H = 48;
    std::vector<std::uint64_t> keys(W * H), keys_b(W * H), keys_s(W * H);
    std::vector<float> lod(W * H), lod_b(W * H);
    std::vector<double> uv(2 * W * H);
    render_feedback(w.scene, cam, {W, H, 0, 2}, keys.data(), lod.data(), uv.data());
    // A bias shifts lambda and the level by the same amount (textureQueryLod with bias).
    render_feedback(w.scene, cam, {W, H, 0.7, 2}, keys_b.data(), lod_b.data());
    int seen = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        if (keys[i] == kNoRequest) {
            EXPECT_EQ(keys_b[i], kNoRequest);
            continue;
        }
        ++seen;
        EXPECT_NEAR(lod_b[i], lod[i] + 0.7f, 1e-5);
        EXPECT_EQ(request_level(keys_b[i]), mip_level(double(lod[i]) + 0.7, 12));
    }
    EXPECT_GT(seen, 100);
    // On a display grid of step 3, lod and uv are the full buffers' every third pixel of
    // every third row; the keys do not change.
    const std::uint32_t S = 3, DW = (W + S - 1) / S, DH = (H + S - 1) / S;
    std::vector<float> lod_s(DW * DH);
    std::vector<double> uv_s(2 * DW * DH);
    FeedbackOptions o{W, H, 0, 2, S};
    render_feedback(w.scene, cam, o, keys_s.data(), lod_s.data(), uv_s.data());
    EXPECT_EQ(keys_s, keys);
    for (std::uint32_t y = 0; y < DH; ++y)
        for (std::uint32_t x = 0; x < DW; ++x) {
            const std::size_t full = std::size_t(y * S) * W + x * S, sub = std::size_t(y) * DW + x;
            if (std::isnan(lod[full])) {
                EXPECT_TRUE(std::isnan(lod_s[sub]));
                continue;
            }
            EXPECT_EQ(lod_s[sub], lod[full]);
            EXPECT_EQ(uv_s[2 * sub], uv[2 * full]);
            EXPECT_EQ(uv_s[2 * sub + 1], uv[2 * full + 1]);
        }
    o.display_step = 0;
    EXPECT_THROW(render_feedback(w.scene, cam, o, keys_s.data()), InvalidArgument);
}

TEST(Feedback, KeysMatchTheTileUnderEveryPixel) {
    // A small painting seen whole, edges and all, at an angle: every key's tile is the one
    // holding the pixel's texel at the key's level (the last tile of a row or column reaches
    // the painting's edge), recomputed here from the uv output.
    const PaintingGeometry tiles(1000, 700);
    const PaintingOnWall wall(tiles);
    const Camera cam({0.3, 0.6, -1.2}, {0.15, -0.05, 1}, {0, 1, 0}, 0.6, 0.6, 1600, 1600);
    const std::uint32_t W = 200, H = 200;
    const auto [keys, lod, uv] = feedback_image(wall.scene, cam, W, H);
    int seen = 0;
    for (std::size_t i = 0; i < keys.size(); ++i) {
        if (keys[i] == kNoRequest) continue;
        ++seen;
        const Request r = unpack_request(keys[i]);
        const double span = 120.0 * (1 << r.level);
        const double x = uv[2 * i] * 1000, y = uv[2 * i + 1] * 700;
        auto tile = [&](double t, std::uint32_t n) {
            return std::min<std::uint32_t>(std::uint32_t(t / span), n - 1);
        };
        const bool near_edge = std::abs(x / span - std::round(x / span)) < 1e-6 ||
                               std::abs(y / span - std::round(y / span)) < 1e-6;
        if (near_edge) continue;
        EXPECT_EQ(r.x, tile(x, tiles.tiles_x(r.level))) << i;
        EXPECT_EQ(r.y, tile(y, tiles.tiles_y(r.level))) << i;
    }
    EXPECT_GT(seen, 5000);
    EXPECT_LT(seen, int(W * H));  // the painting's surroundings are seen too
}

TEST(Feedback, OccludersAndMissesGiveNoRequest) {
    ExhibitionScene scene;
    const PaintingGeometry tiles(1000, 1000);
    scene.add_painting(0, tiles, {0, 1, 0}, {1, 0, 0}, {0, -1, 0}, 1, 1);
    scene.add_box({-0.1, -0.1, -0.5}, {1.1, 1.1, -0.4});  // a box hiding the painting
    scene.commit();
    const Camera cam({0.5, 0.5, -1}, {0, 0, 1}, {0, 1, 0}, 1, 1, 64, 64);
    std::vector<std::uint64_t> keys(8 * 8);
    render_feedback(scene, cam, {}, keys.data());
    for (auto k : keys) EXPECT_EQ(k, kNoRequest);
    ExhibitionScene open;
    EXPECT_THROW(render_feedback(open, cam, {}, keys.data()), InvalidArgument);
    EXPECT_THROW(Camera({0, 0, NAN}, {0, 0, 1}, {0, 1, 0}, 1, 1, 8, 8), InvalidArgument);
    EXPECT_THROW(Camera({0, 0, 0}, {0, 1, 0}, {0, 1, 0}, 1, 1, 8, 8), InvalidArgument);
    EXPECT_THROW(open.add_painting(0, tiles, {0, 0, 0}, {1, 0, 0}, {1, 0, 0}, 1, 1), InvalidArgument);
}

// The block-skipping scan marks exactly what key-by-key fresh() marks, in the same order:
// long runs of one key (skipped eight at a time), runs of kNoRequest, short runs, run ends
// at every offset within a block of eight.
TEST(RequestProcessing, RepeatFilterScanEqualsKeyByKey) {
    std::mt19937 rng(31);
    for (int trial = 0; trial < 50; ++trial) {
        std::vector<std::uint64_t> keys;
        while (keys.size() < 5000) {
            const std::size_t run = 1 + rng() % (rng() % 4 == 0 ? 100 : 9);
            const std::uint64_t key = rng() % 5 == 0 ? kNoRequest : pack_request(0, rng() % 3, rng() % 40, 0);
            keys.insert(keys.end(), run, key);
        }
        const std::size_t n = keys.size() - rng() % 8;
        std::vector<std::uint64_t> one_by_one, scanned;
        RepeatFilter a, b;
        for (std::size_t i = 0; i < n; ++i)
            if (a.fresh(keys[i])) one_by_one.push_back(keys[i]);
        // In two calls, as parallel chunks and buffer boundaries split a scan.
        const std::size_t cut = rng() % n;
        b.scan(keys.data(), cut, [&](std::uint64_t k) { scanned.push_back(k); });
        b.scan(keys.data() + cut, n - cut, [&](std::uint64_t k) { scanned.push_back(k); });
        ASSERT_EQ(scanned, one_by_one) << "trial " << trial;
        // And nothing distinct is lost: the filter only drops repeats.
        std::set<std::uint64_t> all(keys.begin(), keys.begin() + n);
        all.erase(kNoRequest);
        EXPECT_EQ(std::set<std::uint64_t>(scanned.begin(), scanned.end()), all);
    }
}

TEST(RequestProcessing, FourMethodsAgree) {
    const auto paintings = small_paintings();
    const ResidentSet resident = random_residency(paintings, 5);
    FlagArrayProcessor flags(paintings, 2);
    HashProcessor hash(20, 2);  // big table: no collisions expected
    AsyncProcessor async;
    BasicProcessor basic;
    for (unsigned frame = 1; frame <= 5; ++frame) {
        const auto buffers = random_buffers(paintings, 3, 20000 + 1000 * frame, 300, frame);
        const auto views = spans(buffers);
        const auto ref = distinct(buffers);
        const RequestSets b = basic.process(views, resident);
        ASSERT_EQ(sorted(b.requests), std::vector<std::uint64_t>(ref.begin(), ref.end()));
        // Independent responses and commands: straight from the residency set.
        std::vector<std::uint64_t> commands;
        std::map<std::uint64_t, std::uint64_t> resp;
        for (auto k : ref) {
            resp[k] = ancestor_request(k, resident.resident_level(k));
            if (resp[k] != k) commands.push_back(k);
        }
        async.submit(views, frame);
        const auto done = async.drain(resident);
        ASSERT_EQ(done.size(), 1u);
        EXPECT_EQ(done[0].frame, frame);
        for (const RequestSets& s : {b, flags.process(views, resident),
                                     hash.process(views, resident, frame), done[0].sets}) {
            EXPECT_EQ(sorted(s.requests), std::vector<std::uint64_t>(ref.begin(), ref.end()));
            EXPECT_EQ(sorted(s.commands), commands);
            ASSERT_EQ(s.responses.size(), s.requests.size());
            for (std::size_t i = 0; i < s.requests.size(); ++i)
                EXPECT_EQ(s.responses[i], resp[s.requests[i]]);
        }
    }
}

TEST(RequestProcessing, HashCollisionKeepsFinerLevel) {
    // A tiny table forces collisions: every slot must hold exactly the finest (then smallest)
    // of the requests that hash there; all others are lost.
    const auto paintings = small_paintings();
    const ResidentSet resident(paintings);
    HashProcessor hash(6, 2);
    const auto buffers = random_buffers(paintings, 2, 30000, 500, 11);
    const auto ref = distinct(buffers);
    const std::uint64_t frame = 42, salt = HashProcessor::frame_salt(frame);
    std::map<std::uint64_t, std::uint64_t> winner;  // slot -> expected survivor
    for (auto k : ref) {
        const auto s = hash.slot(k, salt);
        auto it = winner.find(s);
        if (it == winner.end()) {
            winner[s] = k;
        } else {
            const auto lk = request_level(k), lh = request_level(it->second);
            if (lk < lh || (lk == lh && k < it->second)) it->second = k;
        }
    }
    std::vector<std::uint64_t> expect;
    for (auto& [s, k] : winner) expect.push_back(k);
    const RequestSets got = hash.process(spans(buffers), resident, frame);
    EXPECT_EQ(sorted(got.requests), sorted(expect));
    EXPECT_LT(got.requests.size(), ref.size());  // something was lost
    // The table is cleared between frames: a frame with a single key returns just it.
    const std::vector<std::vector<std::uint64_t>> one{{pack_request(1, 0, 2, 3)}};
    EXPECT_EQ(hash.process(spans(one), resident, 43).requests, one[0]);
}

namespace {
// Requests lost by `hash` in frame f (against the exact set).
std::set<std::uint64_t> lost_in_frame(HashProcessor& hash, const std::set<std::uint64_t>& ref,
                                      const std::vector<std::vector<std::uint64_t>>& buffers,
                                      const ResidencyLookup& lookup, std::uint64_t frame) {
    const auto got = hash.process(spans(buffers), lookup, frame).requests;
    std::set<std::uint64_t> lost = ref;
    for (auto k : got) lost.erase(k);
    return lost;
}
}  // namespace

TEST(RequestProcessing, FrameSaltStopsRepeatedLosses) {
    // The same feedback on consecutive frames through a small, crowded table (600 requests,
    // 4096 slots, ~7% lost per frame).
    //  - Prime modulus (eq. 1 with m = 65521, L'Ecuyer's a = 17364): the salt permutes
    //    residues, so the same pairs collide in every frame.
    //  - Fixed salt: every loss repeats (trivially).
    //  - Seed salt (m = 2^64, top k bits): a pair colliding in frames F and F + 1 must have
    //    |a (B1 - B2) mod 2^64| < 2^(65 - k) (its collisions differ by a (B1 - B2) between
    //    frames); other repeats need a different partner, and stay rare.
    const auto paintings = small_paintings();
    const ResidentSet resident(paintings);
    const auto buffers = random_buffers(paintings, 2, 40000, 600, 3);
    const auto ref = distinct(buffers);
    const unsigned bits = 12;
    HashProcessor pow2(bits, 2);
    auto prime_pairs = [&](std::uint64_t frame) {
        const std::uint64_t m = 65521, a = 17364, salt = HashProcessor::frame_salt(frame) % m;
        std::map<std::uint64_t, std::vector<std::uint64_t>> by_slot;
        for (auto k : ref) by_slot[a * (k % m * salt % m) % m].push_back(k);
        std::set<std::pair<std::uint64_t, std::uint64_t>> pairs;
        for (auto& [s, ks] : by_slot)
            for (std::size_t i = 0; i < ks.size(); ++i)
                for (std::size_t j = i + 1; j < ks.size(); ++j) pairs.insert({ks[i], ks[j]});
        return pairs;
    };
    std::size_t lost = 0, repeats = 0;
    std::size_t fixed_lost = 0, fixed_repeats = 0;
    auto prev = lost_in_frame(pow2, ref, buffers, resident, 100);
    const auto prime_first = prime_pairs(100);
    ASSERT_FALSE(prime_first.empty());
    const auto fixed_first = lost_in_frame(pow2, ref, buffers, resident, 7);
    auto slots_of = [&](std::uint64_t frame) {
        std::map<std::uint64_t, std::vector<std::uint64_t>> by_slot;
        for (auto k : ref) by_slot[pow2.slot(k, HashProcessor::frame_salt(frame))].push_back(k);
        std::set<std::pair<std::uint64_t, std::uint64_t>> pairs;
        for (auto& [s, ks] : by_slot)
            for (std::size_t i = 0; i < ks.size(); ++i)
                for (std::size_t j = i + 1; j < ks.size(); ++j) pairs.insert({ks[i], ks[j]});
        return pairs;
    };
    auto prev_pairs = slots_of(100);
    for (std::uint64_t f = 101; f < 131; ++f) {
        const auto l = lost_in_frame(pow2, ref, buffers, resident, f);
        lost += l.size();
        for (auto k : l) repeats += prev.count(k);
        prev = l;
        const auto pairs = slots_of(f);
        for (const auto& pr : pairs)
            if (prev_pairs.count(pr)) {
                const auto delta = static_cast<std::int64_t>(kLecuyerA64 * (pr.first - pr.second));
                const double bound = std::ldexp(1.0, 65 - int(bits));
                EXPECT_LT(std::abs(double(delta)), bound) << "pair collided in frames " << f - 1
                                                          << " and " << f;
            }
        prev_pairs = pairs;
        EXPECT_EQ(prime_pairs(f), prime_first) << "frame " << f;
        const auto lf = lost_in_frame(pow2, ref, buffers, resident, 7);  // salt held fixed
        fixed_lost += lf.size();
        for (auto k : lf) fixed_repeats += fixed_first.count(k);
    }
    ASSERT_GT(lost, 100u);  // the table is crowded enough to lose requests every frame
    // Measured 12 of 244 (4.9%): a request lost again needs a new partner, ~ the loss rate.
    EXPECT_LT(repeats * 10, lost) << repeats << " of " << lost;
    EXPECT_EQ(fixed_repeats, fixed_lost);
}

TEST(RequestProcessing, BadKeysThrowAndLeaveProcessorsUsable) {
    const auto paintings = small_paintings();
    const ResidentSet resident(paintings);
    const std::vector<std::vector<std::uint64_t>> bad{{pack_request(0, 0, 1, 1), pack_request(7, 0, 0, 0)}};
    const std::vector<std::vector<std::uint64_t>> good{{pack_request(0, 0, 1, 1)}};
    FlagArrayProcessor flags(paintings, 2);
    HashProcessor hash(10, 2);
    BasicProcessor basic;
    VisibilityLists vis(paintings, 2);
    EXPECT_THROW(flags.process(spans(bad), resident), InvalidArgument);
    EXPECT_THROW(hash.process(spans(bad), resident, 1), InvalidArgument);
    EXPECT_THROW(basic.process(spans(bad), resident), InvalidArgument);
    EXPECT_THROW(vis.process(spans(bad)), InvalidArgument);
    EXPECT_EQ(flags.process(spans(good), resident).requests, good[0]);
    EXPECT_EQ(hash.process(spans(good), resident, 2).requests, good[0]);
    EXPECT_EQ(vis.process(spans(good)).alive, good[0]);
    EXPECT_THROW(HashProcessor(40), InvalidArgument);
}

TEST(VisibilityLists, AliveAndRemoveAgainstSetDifference) {
    const auto paintings = small_paintings();
    VisibilityLists vis(paintings, 2);
    std::set<std::uint64_t> previous;
    for (unsigned frame = 0; frame < 4; ++frame) {
        const auto buffers = random_buffers(paintings, 2, 5000, 120, 100 + frame % 2);
        const auto now = distinct(buffers);
        const auto lists = vis.process(spans(buffers));
        EXPECT_EQ(sorted(lists.alive), std::vector<std::uint64_t>(now.begin(), now.end()));
        std::vector<std::uint64_t> removed;
        std::set_difference(previous.begin(), previous.end(), now.begin(), now.end(),
                            std::back_inserter(removed));
        EXPECT_EQ(sorted(lists.remove), removed);
        previous = now;
    }
}
