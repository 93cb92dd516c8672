// Radius search over the same photons: our adaptive grid (adaptive_grid.h, the renders'
// default), VR-photon-mapping's hash grid (§3.1), nanoflann's kd-tree (a maintained peer) and our
// Jensen kd-tree. Photons: the Cornell box and the office traced with 128^2, 256^2 and 512^2
// photons; queries: the camera's first hits at 128 x 128 pixels; radii 0.02-0.2 times the
// scene's scale (Cornell 1, office 4, as `gigascroll bench photon`). Each query sums the power
// of every photon within r (the heap-free gather's work). The four structures of one
// configuration are registered next to each other, so with --benchmark_repetitions they run
// interleaved on a shared machine.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>
#include <memory>
#include <nanoflann.hpp>
#include <vector>

#include "photon/adaptive_grid.h"
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

const char* const kScenes[] = {"cornell", "office"};
const float kSceneScale[] = {1.0f, 4.0f};

float radius_of(const benchmark::State& st) { return kRadii[st.range(2)] * kSceneScale[st.range(0)]; }

const Workload& workload(int scene_index, int side) {
    static std::map<std::pair<int, int>, std::unique_ptr<Workload>> cache;
    auto& w = cache[{scene_index, side}];
    if (!w) {
        w = std::make_unique<Workload>();
        Scene scene;
        const Camera cam = build_scene(kScenes[scene_index], scene, 128, 128, 0.5f, 1.0f);
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

const Workload& workload(const benchmark::State& st) { return workload(int(st.range(0)), int(st.range(1))); }

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
    const Workload& w = workload(st);
    const float r = radius_of(st);
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

// The adaptive grid's own vectorised sum (what the renders' box gather runs, less the normal
// test); cells_per_radius 0 chooses the cells from the density, as renders do.
void adaptive(benchmark::State& st, float cells_per_radius) {
    const Workload& w = workload(st);
    const float r = radius_of(st);
    const AdaptiveGrid grid(w.photons, r, cells_per_radius);
    std::size_t found = 0;
    for (auto _ : st) {
        float n = 0;
        Vec3f total{0, 0, 0};
        for (const Vec3f& q : w.queries) {
            float c;
            total += grid.sum_in_radius(q, r * r, &c);
            n += c;
        }
        found = std::size_t(n);
        benchmark::DoNotOptimize(total);
    }
    st.counters["cells_per_radius"] = grid.cells_per_radius();
    set_counters(st, w, found);
}
void BM_Adaptive(benchmark::State& st) { adaptive(st, 0.0f); }
// Fixed cells per radius (range 3, in quarters), to tune the automatic choice.
void BM_AdaptiveCells(benchmark::State& st) { adaptive(st, float(st.range(3)) / 4.0f); }

void BM_Nanoflann(benchmark::State& st) {
    const Workload& w = workload(st);
    const float r = radius_of(st);
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
    const Workload& w = workload(st);
    for (auto _ : st) benchmark::DoNotOptimize(HashGrid(w.photons, radius_of(st)).size());
}

void BM_AdaptiveBuild(benchmark::State& st) {
    const Workload& w = workload(st);
    for (auto _ : st) benchmark::DoNotOptimize(AdaptiveGrid(w.photons, radius_of(st)).size());
}

void BM_NanoflannBuild(benchmark::State& st) {
    const Workload& w = workload(st);
    const Cloud cloud{&w.photons};
    for (auto _ : st) {
        NanoTree tree(3, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
        tree.buildIndex();
        benchmark::DoNotOptimize(tree.size(tree));
    }
}

void search(const char* name, void (*fn)(benchmark::State&), std::vector<std::int64_t> args) {
    std::vector<std::string> names = {"scene", "side", "r_index", "quarter_cells"};
    names.resize(args.size());
    benchmark::RegisterBenchmark(name, fn)
        ->Args(args)
        ->ArgNames(names)
        ->Unit(benchmark::kMillisecond)
        ->MinTime(0.1);
}

}  // namespace

int main(int argc, char** argv) {
    // Configuration-major order: the structures of one (scene, photons, radius) run back to back.
    for (int scene = 0; scene < 2; ++scene)
        for (int side : {128, 256, 512})
            for (int r = 0; r < 4; ++r) {
                const std::vector<std::int64_t> a = {scene, side, r};
                search("BM_Adaptive", BM_Adaptive, a);
                search("BM_HashGrid", BM_HashGrid, a);
                search("BM_Nanoflann", BM_Nanoflann, a);
                search("BM_KdTree", BM_KdTree, a);
                for (int q : {1, 2, 4, 8, 12}) {
                    auto b = a;
                    b.push_back(q);
                    search("BM_AdaptiveCells", BM_AdaptiveCells, b);
                }
            }
    for (int scene = 0; scene < 2; ++scene) {
        using Fn = void (*)(benchmark::State&);
        const std::pair<const char*, Fn> builds[] = {
            {"BM_AdaptiveBuild", BM_AdaptiveBuild}, {"BM_HashGridBuild", BM_HashGridBuild},
            {"BM_NanoflannBuild", BM_NanoflannBuild}};
        for (auto [name, fn] : builds)
            benchmark::RegisterBenchmark(name, fn)->Args({scene, 512, 1})->ArgNames({"scene", "side", "r_index"})
                ->Unit(benchmark::kMillisecond);
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
