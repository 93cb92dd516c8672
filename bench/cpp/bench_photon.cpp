// Radius search over the same photons: our hash grid (seed 001 §3.1) against nanoflann's
// kd-tree (a maintained peer) and our Jensen kd-tree. Photons: the Cornell box traced with
// 128^2, 256^2 and 512^2 photons; queries: the camera's first hits at 128 x 128 pixels.
// Each query sums the power of every photon within r (the heap-free gather's work).
#include <benchmark/benchmark.h>

#include <map>
#include <memory>
#include <nanoflann.hpp>
#include <vector>

#include "photon/hash_grid.h"
#include "photon/kd_tree.h"
#include "photon/photon_tracer.h"
#include "photon/scenes.h"

using namespace gigascroll;

namespace {

const float kRadii[] = {0.02f, 0.05f, 0.1f, 0.2f};

struct Workload {
    std::vector<Photon> photons;
    std::vector<Vec3f> queries;
};

const Workload& workload(int side) {
    static std::map<int, std::unique_ptr<Workload>> cache;
    auto& w = cache[side];
    if (!w) {
        w = std::make_unique<Workload>();
        Scene scene;
        const Camera cam = build_cornell(scene, 128, 128);
        scene.commit();
        w->photons = trace_photons(scene, std::uint64_t(side) * side, 1);
        for (int y = 0; y < int(cam.height); ++y)
            for (int x = 0; x < int(cam.width); ++x) {
                Hit h;
                if (scene.intersect(cam.ray_origin(), cam.ray_direction(x + 0.5f, y + 0.5f), h)) w->queries.push_back(h.p);
            }
    }
    return *w;
}

// nanoflann's dataset adaptor over our photons.
struct Cloud {
    const std::vector<Photon>* p;
    std::size_t kdtree_get_point_count() const { return p->size(); }
    float kdtree_get_pt(std::size_t i, std::size_t d) const { return (*p)[i].p[int(d)]; }
    template <class B>
    bool kdtree_get_bbox(B&) const { return false; }
};
using NanoTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Cloud>, Cloud, 3>;

// Sums power within r without storing matches, as our gathers do.
struct SumResult {
    float r2;
    const std::vector<Photon>* p;
    Vec3f sum{0, 0, 0};
    std::size_t n = 0;
    void init() {}
    void clear() {}
    std::size_t size() const { return n; }
    bool full() const { return true; }
    bool addPoint(float d2, std::size_t i) {
        if (d2 < r2) { sum += (*p)[i].power; ++n; }
        return true;
    }
    float worstDist() const { return r2; }
};

void set_counters(benchmark::State& st, const Workload& w, std::size_t found) {
    st.counters["photons"] = double(w.photons.size());
    st.counters["queries"] = double(w.queries.size());
    st.counters["found/query"] = double(found) / double(w.queries.size());
}

// Sums the power of every photon within r of each query through `index.for_each_in_radius`.
template <typename Index>
void radius_search(benchmark::State& st) {
    const Workload& w = workload(int(st.range(0)));
    const float r = kRadii[st.range(1)];
    const Index index(w.photons, r);
    std::size_t found = 0;
    for (auto _ : st) {
        found = 0;
        Vec3f total{0, 0, 0};
        for (const Vec3f& q : w.queries) {
            float r2 = r * r;
            index.for_each_in_radius(q, r2, [&](const Photon& p, float) { total += p.power; ++found; });
        }
        benchmark::DoNotOptimize(total);
    }
    set_counters(st, w, found);
}

// The kd-tree ignores the radius at build time; this adapter gives it the grid's constructor.
struct RadiusKdTree : KdTree {
    RadiusKdTree(const std::vector<Photon>& photons, float) : KdTree(photons) {}
};

void BM_HashGrid(benchmark::State& st) { radius_search<HashGrid>(st); }
void BM_KdTree(benchmark::State& st) { radius_search<RadiusKdTree>(st); }

void BM_Nanoflann(benchmark::State& st) {
    const Workload& w = workload(int(st.range(0)));
    const float r = kRadii[st.range(1)];
    const Cloud cloud{&w.photons};
    NanoTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree.buildIndex();
    std::size_t found = 0;
    for (auto _ : st) {
        found = 0;
        Vec3f total{0, 0, 0};
        for (const Vec3f& q : w.queries) {
            SumResult res{r * r, &w.photons};
            const float qp[3] = {q.x, q.y, q.z};
            tree.radiusSearchCustomCallback(qp, res, nanoflann::SearchParams(32, 0.0f, false));
            total += res.sum;
            found += res.n;
        }
        benchmark::DoNotOptimize(total);
    }
    set_counters(st, w, found);
}

void BM_HashGridBuild(benchmark::State& st) {
    const Workload& w = workload(int(st.range(0)));
    for (auto _ : st) benchmark::DoNotOptimize(HashGrid(w.photons, kRadii[st.range(1)]).size());
}

void BM_NanoflannBuild(benchmark::State& st) {
    const Workload& w = workload(int(st.range(0)));
    const Cloud cloud{&w.photons};
    for (auto _ : st) {
        NanoTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
        tree.buildIndex();
        benchmark::DoNotOptimize(tree.size(tree));
    }
}

void search_args(benchmark::internal::Benchmark* b) {
    for (int side : {128, 256, 512})
        for (int r = 0; r < 4; ++r) b->Args({side, r});
    b->ArgNames({"side", "r_index"})->Unit(benchmark::kMillisecond)->MinTime(0.2);
}

}  // namespace

BENCHMARK(BM_HashGrid)->Apply(search_args);
BENCHMARK(BM_KdTree)->Apply(search_args);
BENCHMARK(BM_Nanoflann)->Apply(search_args);
BENCHMARK(BM_HashGridBuild)->Args({512, 1})->Unit(benchmark::kMillisecond);
BENCHMARK(BM_NanoflannBuild)->Args({512, 1})->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
