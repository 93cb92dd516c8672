// The adaptive grid against brute force, nanoflann and VR-photon-mapping's grid: the same photons found
// for random and camera-hit queries at every cell size, flux sums in storage order
// bit-identical to brute force, far-from-origin scenes and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <nanoflann.hpp>
#include <memory>
#include <random>
#include <vector>

#include "common/error.h"
#include "photon/adaptive_grid.h"
#include "photon/hash_grid.h"
#include "photon/photon_map.h"
#include "photon/photon_tracer.h"
#include "photon/random_photons.h"
#include "photon/renderer.h"
#include "photon/small_cornell.h"

using namespace gigascroll;

namespace {

bool less3(Vec3f a, Vec3f b) { return a.x < b.x || (a.x == b.x && (a.y < b.y || (a.y == b.y && a.z < b.z))); }

std::vector<Vec3f> sorted(std::vector<Vec3f> v) {
    std::sort(v.begin(), v.end(), less3);
    return v;
}

std::vector<Vec3f> brute(const std::vector<Photon>& ph, Vec3f q, float r2) {
    std::vector<Vec3f> out;
    for (const Photon& p : ph) {
        const Vec3f d = p.p - q;
        if (dot(d, d) <= r2) out.push_back(p.p);
    }
    return sorted(out);
}

template <typename Map>
std::vector<Vec3f> found(const Map& m, Vec3f q, float r2) {
    std::vector<Vec3f> out;
    m.for_each_in_radius(q, r2, [&](const Photon& p, float) { out.push_back(p.p); });
    return sorted(out);
}

void expect_equal(const std::vector<Vec3f>& a, const std::vector<Vec3f>& b) {
    ASSERT_EQ(a.size(), b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
        ASSERT_EQ(a[i].x, b[i].x);
        ASSERT_EQ(a[i].y, b[i].y);
        ASSERT_EQ(a[i].z, b[i].z);
    }
}

// Brute force over the grid's own storage order (runs are visited in increasing storage
// index, so a sequential float sum must match bit for bit).
Vec3f brute_sum_in_order(const std::vector<Photon>& ordered, Vec3f q, float r2, int& count) {
    Vec3f s{0, 0, 0};
    count = 0;
    for (const Photon& p : ordered) {
        const Vec3f d = p.p - q;
        if (dot(d, d) <= r2) {
            s += p.power;
            ++count;
        }
    }
    return s;
}

struct Cloud {
    const std::vector<Photon>* p;
    std::size_t kdtree_get_point_count() const { return p->size(); }
    float kdtree_get_pt(std::size_t i, std::size_t d) const { return (*p)[i].p[int(d)]; }
    template <class B>
    bool kdtree_get_bbox(B&) const { return false; }
};
using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud, 3>;

std::vector<Vec3f> nanoflann_found(const NanoTree& tree, const std::vector<Photon>& ph, Vec3f q, float r2) {
    std::vector<std::pair<std::uint32_t, float>> matches;
    const float qp[3] = {q.x, q.y, q.z};
    // nanoflann keeps d2 < radius; nudge it up one ulp so it keeps d2 <= r2 like the gathers.
    tree.radiusSearch(qp, std::nextafter(r2, 1e30f), matches, nanoflann::SearchParams(32, 0.0f, false));
    std::vector<Vec3f> out;
    for (const auto& m : matches) out.push_back(ph[m.first].p);
    return sorted(out);
}

}  // namespace

TEST(AdaptiveGrid, FindsExactlyTheBruteForceSetAtEveryCellSize) {
    std::mt19937 rng(11);
    auto ph = random_photons(40000, 7);
    std::uniform_real_distribution<float> power(0.1f, 2.0f);
    for (Photon& p : ph) p.power = {power(rng), power(rng), power(rng)};
    const float r = 0.15f;
    std::uniform_real_distribution<float> u(-1.2f, 1.2f);  // some queries outside the photons' box
    std::size_t total = 0;
    for (float cells : {0.0f, 0.25f, 0.5f, 1.0f, 2.0f, 3.0f, 4.0f}) {
        const AdaptiveGrid grid(ph, r, cells);
        ASSERT_EQ(grid.size(), ph.size());
        for (int i = 0; i < 200; ++i) {
            const Vec3f q{u(rng), u(rng), u(rng) * 0.3f};
            const float rq = i % 3 == 0 ? r : r * (0.2f + 0.7f * float(i % 7) / 7.0f);
            const auto ref = brute(ph, q, rq * rq);
            total += ref.size();
            expect_equal(found(grid, q, rq * rq), ref);
            // The vectorised sums: the same count, and the flux of brute force in storage order.
            int n_ref = 0;
            const Vec3f s_ref = brute_sum_in_order(grid.photons(), q, rq * rq, n_ref);
            float n = 0;
            const Vec3f s = grid.sum_in_radius(q, rq * rq, &n);
            EXPECT_EQ(n, float(n_ref));
            EXPECT_NEAR(s.x, s_ref.x, 1e-5f * (1 + s_ref.x));
            EXPECT_NEAR(s.z, s_ref.z, 1e-5f * (1 + s_ref.z));
            // The radius gather of gather.h walks the runs in storage order: bit-identical.
            float r2 = rq * rq;
            Vec3f seq{0, 0, 0};
            grid.for_each_in_radius(q, r2, [&](const Photon& p, float) { seq += p.power; });
            EXPECT_EQ(seq.x, s_ref.x);
            EXPECT_EQ(seq.y, s_ref.y);
            EXPECT_EQ(seq.z, s_ref.z);
        }
    }
    EXPECT_GT(total, 50000u);  // the queries did find photons
}

TEST(AdaptiveGrid, BoxSumMatchesBruteForceWithNormals) {
    std::mt19937 rng(3);
    auto ph = random_photons(20000, 9);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    for (Photon& p : ph) p.n = normalize(Vec3f(u(rng), u(rng), u(rng)) + Vec3f(0, 0, 0.3f));
    const AdaptiveGrid grid(ph, 0.1f, 2.0f);
    for (int i = 0; i < 200; ++i) {
        const Vec3f q{u(rng), u(rng), u(rng) * 0.3f};
        const Vec3f n = normalize(Vec3f(u(rng), u(rng), u(rng)));
        double ref = 0;
        int count = 0;
        for (const Photon& p : ph)
            if (dot(p.p - q, p.p - q) <= 0.01f && dot(p.n, n) > kNormalAgreement) {
                ref += p.power.y;
                ++count;
            }
        float c = 0;
        const Vec3f s = grid.sum_box(q, n, 0.01f, &c);
        EXPECT_EQ(c, float(count));
        EXPECT_NEAR(s.y, ref, 1e-5 * (1 + ref));
    }
}

TEST(AdaptiveGrid, CornellPhotonsMatchNanoflannSeedGridAndBruteForce) {
    SmallCornell box(32, 1 << 14);
    const std::vector<Photon> ph = trace_photons(box.scene, 1 << 14, 1);
    ASSERT_GT(ph.size(), 5000u);
    const Cloud cloud{&ph};
    NanoTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    std::size_t total = 0;
    for (float r : {0.02f, 0.05f, 0.1f, 0.2f}) {
        const AdaptiveGrid grid(ph, r);
        const HashGrid seed(ph, r);
        for (int y = 0; y < 32; y += 3)
            for (int x = 0; x < 32; x += 3) {
                Hit h;
                if (!box.scene.intersect(box.cam.ray_origin(), box.cam.ray_direction(x + 0.5f, y + 0.5f), h)) continue;
                const auto ref = brute(ph, h.p, r * r);
                total += ref.size();
                const auto got = found(grid, h.p, r * r);
                expect_equal(got, ref);
                expect_equal(found(seed, h.p, r * r), ref);
                expect_equal(nanoflann_found(tree, ph, h.p, r * r), ref);
            }
    }
    EXPECT_GT(total, 10000u);
}

TEST(AdaptiveGrid, RendersTheSeedGridsImage) {
    SmallCornell box(24, 20000);
    for (bool two_pass : {false, true}) {
        box.settings.pipeline = two_pass ? Pipeline::TwoPass : Pipeline::Fused;
        box.settings.grid = GridKind::Hash;
        RenderStats st;
        const auto seed = Renderer(box.scene, box.settings).render(box.cam, st);
        box.settings.grid = GridKind::Adaptive;
        const auto ours = Renderer(box.scene, box.settings).render(box.cam, st);
        ASSERT_EQ(seed.size(), ours.size());
        double sum = 0;
        for (std::size_t i = 0; i < seed.size(); ++i) {
            EXPECT_NEAR(ours[i], seed[i], 1e-5f * (1.0f + seed[i]));
            sum += seed[i];
        }
        EXPECT_GT(sum, 0.0);
    }
}

TEST(AdaptiveGrid, FarFromTheOriginAndDegenerateInput) {
    // Photons around (1e4, -3e4, 5e3) at a radius of a few float ulps' worth of cells.
    auto ph = random_photons(5000, 4, 0.05f);
    for (Photon& p : ph) p.p += Vec3f(1e4f, -3e4f, 5e3f);
    std::mt19937 rng(5);
    std::uniform_int_distribution<std::size_t> pick(0, ph.size() - 1);
    for (float cells : {0.0f, 4.0f}) {
        const AdaptiveGrid grid(ph, 0.004f, cells);
        for (int i = 0; i < 100; ++i) {
            const Vec3f q = ph[pick(rng)].p + Vec3f(0.001f, -0.002f, 0.0005f) * float(i % 3);
            expect_equal(found(grid, q, 0.004f * 0.004f), brute(ph, q, 0.004f * 0.004f));
        }
    }
    // All photons on one point, an empty grid, NaN queries.
    std::vector<Photon> same(100, ph[0]);
    const AdaptiveGrid one(same, 0.1f);
    float c = 0;
    one.sum_in_radius(ph[0].p, 0.01f, &c);
    EXPECT_EQ(c, 100.0f);
    const AdaptiveGrid none(std::vector<Photon>{}, 0.1f);
    EXPECT_EQ(none.sum_in_radius({0, 0, 0}, 0.01f, &c).x, 0.0f);
    EXPECT_EQ(c, 0.0f);
    one.sum_in_radius({NAN, 0, 0}, 0.01f, &c);
    EXPECT_EQ(c, 0.0f);
    EXPECT_THROW(AdaptiveGrid(ph, 0.0f), InvalidArgument);
    EXPECT_THROW(AdaptiveGrid(ph, NAN), InvalidArgument);
    EXPECT_THROW(AdaptiveGrid(ph, 0.1f, 8.0f), InvalidArgument);
    auto bad = ph;
    bad[3].p.x = INFINITY;
    EXPECT_THROW(AdaptiveGrid(bad, 0.1f), InvalidArgument);
}

TEST(AdaptiveGrid, PhotonMapDispatchesToIt) {
    const auto ph = random_photons(5000, 8);
    const PhotonMap map(ph, 0.1f, GridKind::Adaptive);
    ASSERT_NE(map.adaptive(), nullptr);
    EXPECT_EQ(map.grid(), nullptr);
    EXPECT_EQ(parse_grid_kind("adaptive"), GridKind::Adaptive);
    const Vec3f q{0.1f, 0.2f, 0.0f};
    const auto idx = map.query_radius(q, 0.08f);
    std::vector<Vec3f> got;
    for (auto i : idx) got.push_back(map.photons()[i].p);
    expect_equal(sorted(got), brute(ph, q, 0.08f * 0.08f));
    EXPECT_THROW(map.query_radius(q, 0.2f), InvalidArgument);
}

TEST(AdaptiveGrid, FullDiscPassMatchesTheGenericDiscGather) {
    // Photons on the plane z = 0 (within the disc's slab) and off it, normals up or tilted.
    std::mt19937 rng(21);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<Photon> ph(30000);
    for (std::size_t i = 0; i < ph.size(); ++i) {
        Photon& p = ph[i];
        p.p = {u(rng), u(rng), i % 3 ? 0.004f * u(rng) : 0.3f * u(rng)};
        p.n = i % 5 ? Vec3f(0, 0, 1) : normalize(Vec3f(u(rng), u(rng), 0.5f));
        p.power = {0.5f + 0.5f * u(rng), 1, 2};
    }
    const AdaptiveGrid grid(ph, 0.1f);
    for (int i = 0; i < 300; ++i) {
        const Vec3f x{u(rng), u(rng), 0.002f * u(rng)};
        const Vec3f n = i % 2 ? Vec3f(0, 0, 1) : normalize(Vec3f(0.1f * u(rng), 0.1f * u(rng), 1));
        const SurfaceDisc d = full_surface_disc(x, n, 0.1f * (0.5f + 0.5f * std::fabs(u(rng))));
        float c_ref = 0, f_ref = 0, c = -1, f = -1;
        const Vec3f s_ref = gather_disc(grid, d, &c_ref, &f_ref);
        const Vec3f s = grid.sum_full_disc(d, &c, &f);
        EXPECT_EQ(c, c_ref);
        EXPECT_EQ(f, f_ref);
        EXPECT_NEAR(s.x, s_ref.x, 1e-5f * (1 + std::fabs(s_ref.x)));
        EXPECT_NEAR(s.z, s_ref.z, 1e-5f * (1 + s_ref.z));
        // The early-out variant: no foreign photon exactly when the full pass finds none, and
        // then the full pass's sums bit for bit.
        Vec3f s_early{-1, -1, -1};
        float c_early = -1;
        const bool clean = grid.sum_full_disc_unless_foreign(d, &s_early, &c_early);
        EXPECT_EQ(clean, f_ref == 0);
        if (clean) {
            EXPECT_EQ(c_early, c);
            EXPECT_EQ(s_early.x, s.x);
            EXPECT_EQ(s_early.z, s.z);
        }
    }
}

TEST(AdaptiveGrid, FullDiscPassStopsAtAForeignPhotonOnly) {
    // Photons on the floor z = 0 (normal up) and on a wall x = 0.5 (normal -x): discs on the
    // floor away from the wall hold no foreign photon (the full pass's sums, bit for bit),
    // those within r of it do (found however the rows are ordered).
    std::mt19937 rng(24);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<Photon> ph(30000);
    for (std::size_t i = 0; i < ph.size(); ++i) {
        Photon& p = ph[i];
        const bool wall = i % 4 == 0;
        p.p = wall ? Vec3f(0.5f, u(rng), 0.5f + 0.5f * u(rng)) : Vec3f(u(rng), u(rng), 0);
        p.n = wall ? Vec3f(-1, 0, 0) : Vec3f(0, 0, 1);
        p.power = {0.5f + 0.5f * u(rng), 1, 2};
    }
    const AdaptiveGrid grid(ph, 0.1f);
    int clean_discs = 0, foreign_discs = 0;
    for (int i = 0; i < 400; ++i) {
        const Vec3f x{0.7f * u(rng), u(rng), 0};
        const SurfaceDisc d = full_surface_disc(x, {0, 0, 1}, 0.1f);
        float c = 0, f = 0;
        const Vec3f s = grid.sum_full_disc(d, &c, &f);
        Vec3f s_early{-1, -1, -1};
        float c_early = -1;
        const bool clean = grid.sum_full_disc_unless_foreign(d, &s_early, &c_early);
        EXPECT_EQ(clean, f == 0);
        if (std::fabs(x.x - 0.5f) > 0.1f + 1e-3f) EXPECT_TRUE(clean);  // no wall photon within r
        if (clean) {
            EXPECT_EQ(c_early, c);
            EXPECT_EQ(s_early.x, s.x);
            EXPECT_EQ(s_early.z, s.z);
        }
        ++(clean ? clean_discs : foreign_discs);
    }
    EXPECT_GT(clean_discs, 50);  // both outcomes are exercised
    EXPECT_GT(foreign_discs, 20);
}

TEST(AdaptiveGrid, ClippedDiscPassMatchesBruteForce) {
    // Discs clipped per sector (as make_surface_disc leaves them: some sectors short, some
    // empty) against brute force over every photon with SurfaceDisc::contains: the same
    // photons (count and rejected count exact), power within float rounding. Photons also
    // sit on the sector boundaries (angles k * 22.5 degrees), where the branch-free sector
    // must agree with SurfaceDisc::sector.
    std::mt19937 rng(22);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    std::vector<Photon> ph(40000);
    for (std::size_t i = 0; i < ph.size(); ++i) {
        Photon& p = ph[i];
        if (i % 4 == 0) {  // on a sector boundary ray through a grid point
            const float a = float(int(i / 4) % 16) * float(M_PI) / 8.0f, rho = 0.1f * std::fabs(u(rng));
            const Vec3f c{std::round(u(rng) * 4) / 4, std::round(u(rng) * 4) / 4, 0};
            p.p = c + Vec3f(std::cos(a), std::sin(a), 0) * rho;
        } else {
            p.p = {u(rng), u(rng), i % 3 ? 0.004f * u(rng) : 0.3f * u(rng)};
        }
        p.n = i % 5 ? Vec3f(0, 0, 1) : normalize(Vec3f(u(rng), u(rng), 0.5f));
        p.power = {0.5f + 0.5f * u(rng), 1, 2};
    }
    const AdaptiveGrid grid(ph, 0.1f);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    for (int i = 0; i < 400; ++i) {
        const bool on_grid_point = i % 4 == 0;
        const Vec3f x = on_grid_point ? Vec3f(std::round(u(rng) * 4) / 4, std::round(u(rng) * 4) / 4, 0)
                                      : Vec3f(u(rng), u(rng), 0.002f * u(rng));
        const Vec3f n = i % 2 || on_grid_point ? Vec3f(0, 0, 1) : normalize(Vec3f(0.1f * u(rng), 0.1f * u(rng), 1));
        SurfaceDisc d = full_surface_disc(x, n, 0.1f * (0.5f + 0.5f * std::fabs(u(rng))));
        for (float& r2 : d.reach2) {
            const float k = unit(rng);
            r2 *= k < 0.2f ? 0.0f : k < 0.5f ? 1.0f : k * k;
        }
        float c_ref = 0, f_ref = 0;
        Vec3f s_ref{0, 0, 0};
        const float r2 = d.r * d.r;
        for (const Photon& p : ph) {
            const Vec3f e = p.p - d.x;
            if (!(dot(e, e) <= r2)) continue;
            if (dot(p.n, d.n) > 0.5f && d.contains(p.p)) {
                s_ref += p.power;
                c_ref += 1;
            } else {
                f_ref += 1;
            }
        }
        float c = -1, f = -1;
        const Vec3f s = grid.sum_disc(d, &c, &f);
        EXPECT_EQ(c, c_ref);
        EXPECT_EQ(f, f_ref);
        EXPECT_NEAR(s.x, s_ref.x, 1e-5f * (1 + std::fabs(s_ref.x)));
        EXPECT_NEAR(s.z, s_ref.z, 1e-5f * (1 + s_ref.z));
        // And the generic gather over the same grid agrees.
        float c_gen = 0;
        gather_disc(grid, d, &c_gen);
        EXPECT_EQ(c, c_gen);
    }
}

TEST(AdaptiveGrid, ARecycledGridAnswersAsAFreshOne) {
    // A grid built on the storage of a previous one (larger, then smaller photon sets, other
    // radii and so other cell sizes) finds and sums exactly what a fresh grid does.
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    auto photons = [&](std::size_t n) {
        std::vector<Photon> ph(n);
        for (Photon& p : ph) {
            p.p = {u(rng), u(rng), 0.01f * u(rng)};
            p.n = {0, 0, 1};
            p.power = {0.5f + 0.5f * u(rng), 1, 2};
        }
        return ph;
    };
    auto previous = std::make_unique<AdaptiveGrid>(photons(60000), 0.05f);
    for (auto [n, r] : {std::pair{5000, 0.2f}, {40000, 0.03f}, {80000, 0.1f}, {100, 0.5f}}) {
        const std::vector<Photon> ph = photons(std::size_t(n));
        const AdaptiveGrid fresh(ph, r);
        auto recycled = std::make_unique<AdaptiveGrid>(ph, r, 0.0f, previous.get());
        ASSERT_EQ(recycled->size(), fresh.size());
        EXPECT_EQ(recycled->cell_edge(), fresh.cell_edge());
        for (std::size_t i = 0; i < ph.size(); ++i) EXPECT_EQ(recycled->photons()[i].p.x, fresh.photons()[i].p.x);
        for (int i = 0; i < 100; ++i) {
            const Vec3f q{u(rng), u(rng), 0};
            float c0 = 0, c1 = 0;
            const Vec3f a = fresh.sum_box(q, {0, 0, 1}, r * r, &c0), b = recycled->sum_box(q, {0, 0, 1}, r * r, &c1);
            EXPECT_EQ(c0, c1);
            EXPECT_EQ(a.x, b.x);
            EXPECT_EQ(c0, float(brute(ph, q, r * r).size()));
        }
        previous = std::move(recycled);
    }
}

// Above 2^16 photons and with few cells per photon the build sorts on several threads: the
// same storage order as a serial build (so the same sums, bit for bit), and the set brute
// force finds.
TEST(AdaptiveGrid, ABuildOnSeveralThreadsEqualsASerialOne) {
    const std::vector<Photon> ph = random_photons(150000, 11);
    for (float k : {0.0f, 0.5f, 2.0f}) {
        const AdaptiveGrid serial(ph, 0.05f, k, nullptr, 1);
        for (unsigned threads : {2u, 3u, 0u}) {
            const AdaptiveGrid parallel(ph, 0.05f, k, nullptr, threads);
            ASSERT_EQ(parallel.cell_count(), serial.cell_count());
            ASSERT_EQ(parallel.size(), serial.size());
            for (std::size_t i = 0; i < ph.size(); ++i) {
                ASSERT_EQ(parallel.photons()[i].p.x, serial.photons()[i].p.x) << i;
                ASSERT_EQ(parallel.photons()[i].p.y, serial.photons()[i].p.y) << i;
                ASSERT_EQ(parallel.photons()[i].p.z, serial.photons()[i].p.z) << i;
            }
        }
        const AdaptiveGrid parallel(ph, 0.05f, k, nullptr, 2);
        std::mt19937 rng(5);
        std::uniform_real_distribution<float> u(-1, 1);
        for (int q = 0; q < 20; ++q) {
            const Vec3f x(u(rng), u(rng), 0.3f * u(rng));
            expect_equal(found(parallel, x, 0.05f * 0.05f), brute(ph, x, 0.05f * 0.05f));
            float cs = 0, cp = 0;
            const Vec3f ss = serial.sum_in_radius(x, 0.0025f, &cs), sp = parallel.sum_in_radius(x, 0.0025f, &cp);
            EXPECT_EQ(ss.x, sp.x);
            EXPECT_EQ(cs, cp);
            EXPECT_EQ(cp, float(brute(ph, x, 0.0025f).size()));
        }
    }
}
