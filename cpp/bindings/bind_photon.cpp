// Python bindings of the photon mapper. Arrays come in as C-contiguous float32/int64 numpy
// arrays without copies (the Python layer in gigascroll/photon.py converts and validates
// user input first) and images go out as float32 (H, W, 3) arrays owning their buffers.
#include <nanobind/nanobind.h>
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <string>
#include <vector>

#include "bindings/bindings.h"
#include "bindings/arrays.h"
#include "common/error.h"
#include "photon/photon_map.h"
#include "photon/photon_tracer.h"
#include "photon/progressive.h"
#include "photon/renderer.h"
#include "photon/scene.h"
#include "photon/scenes.h"
#include "photon/stereo.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {
using namespace gigascroll;

using FloatArray = nb::ndarray<const float, nb::c_contig, nb::device::cpu>;
using IndexArray = nb::ndarray<const std::int64_t, nb::c_contig, nb::device::cpu>;
using Out = nb::ndarray<nb::numpy, float>;

Vec3f vec(const std::array<float, 3>& a) { return {a[0], a[1], a[2]}; }

Out photons_field(const std::vector<Photon>& ph, int field) {
    std::vector<float> v(ph.size() * 3);
    for (std::size_t i = 0; i < ph.size(); ++i) {
        const Vec3f x = field == 0 ? ph[i].p : (field == 1 ? ph[i].power : ph[i].n);
        v[3 * i] = x.x; v[3 * i + 1] = x.y; v[3 * i + 2] = x.z;
    }
    return to_numpy(std::move(v), {ph.size(), 3});
}

std::vector<Photon> photons_from(const FloatArray& positions) {
    require(positions.ndim() == 2 && positions.shape(1) == 3, "PhotonMap: positions must have shape (N, 3)");
    std::vector<Photon> ph(positions.shape(0));
    const float* p = positions.data();
    for (std::size_t i = 0; i < ph.size(); ++i) {
        ph[i].p = {p[3 * i], p[3 * i + 1], p[3 * i + 2]};
        require(is_finite(ph[i].p), "PhotonMap: positions must be finite");
        ph[i].power = {1, 1, 1};
        ph[i].n = {0, 0, 1};
    }
    return ph;
}

RenderSettings make_settings(std::uint64_t photons, float radius, const std::string& grid,
                             const std::string& gather, int k, const std::string& kernel, int spp,
                             int light_samples, std::uint64_t seed, const std::string& pipeline,
                             bool cooperative, bool direct, bool indirect, unsigned threads,
                             const std::string& mode, bool disc) {
    RenderSettings s;
    s.photons = photons;
    s.gather.radius = radius;
    s.grid = parse_grid_kind(grid);
    s.gather.knn = parse_gather_is_knn(gather);
    s.gather.k = k;
    s.gather.kernel = parse_kernel(kernel);
    s.spp = spp;
    s.light_samples = light_samples;
    s.seed = seed;
    s.pipeline = parse_pipeline(pipeline);
    s.cooperative = cooperative;
    s.direct = direct;
    s.indirect = indirect;
    s.threads = threads;
    s.hash_mode = parse_hash_mode(mode);
    s.gather.disc = disc;
    s.validate();
    return s;
}

nb::dict stats_dict(const RenderStats& st) {
    nb::dict d;
    d["photon_seconds"] = st.photon_seconds;
    d["build_seconds"] = st.build_seconds;
    d["trace_seconds"] = st.trace_seconds;
    d["gather_seconds"] = st.gather_seconds;
    d["total_seconds"] = st.total_seconds;
    d["photons_stored"] = st.photons_stored;
    d["photon_pass_skipped"] = st.photon_pass_skipped;
    d["gathers"] = st.gathers;
    d["gathers_skipped"] = st.gathers_skipped;
    d["shadow_rays"] = st.shadow_rays;
    d["shadow_rays_skipped"] = st.shadow_rays_skipped;
    d["reused_pixels"] = st.reused_pixels;
    return d;
}

#define RENDER_ARGS                                                                                   \
    "photons"_a, "radius"_a, "grid"_a = "adaptive", "gather"_a = "radius", "k"_a = 50, "kernel"_a = "box", \
        "spp"_a = 1, "light_samples"_a = 1, "seed"_a = 0, "pipeline"_a = "fused", "cooperative"_a = false, \
        "direct"_a = true, "indirect"_a = true, "threads"_a = 0, "hash_mode"_a = "auto", "disc"_a = false

}  // namespace

void bind_photon(nb::module_& m) {
    nb::class_<Scene>(m, "_Scene", "Embree scene of Lambertian triangle meshes (see gigascroll.Scene).")
        .def(nb::init<>())
        .def("_add_mesh",
             [](Scene& s, const FloatArray& v, const IndexArray& t, const FloatArray& albedo,
                std::array<float, 3> emission) {
                 require(v.ndim() == 2 && v.shape(1) == 3, "add_mesh: vertices must have shape (N, 3)");
                 require(t.ndim() == 2 && t.shape(1) == 3, "add_mesh: triangles must have shape (M, 3)");
                 const bool per_tri = albedo.ndim() == 2;
                 require((albedo.ndim() == 1 && albedo.shape(0) == 3) ||
                             (per_tri && albedo.shape(0) == t.shape(0) && albedo.shape(1) == 3),
                         "add_mesh: albedo must have shape (3,) or (M, 3)");
                 return s.add_mesh(v.data(), v.shape(0), t.data(), t.shape(0), albedo.data(), per_tri,
                                   vec(emission));
             })
        .def("commit", [](Scene& s) {
            nb::gil_scoped_release release;
            s.commit();
        }, "Builds the BVH and the emitter distribution; no meshes can be added afterwards.")
        .def_prop_ro("committed", &Scene::committed)
        .def_prop_ro("triangle_count", &Scene::triangle_count)
        .def_prop_ro("emitter_count", &Scene::emitter_count)
        .def_prop_ro("emitted_power", [](const Scene& s) {
            const Vec3f p = s.emitted_power();
            return std::array<float, 3>{p.x, p.y, p.z};
        }, "Total emitted flux: sum of pi * area * radiance over the emitters (RGB).")
        .def_prop_ro("bounds", [](const Scene& s) {
            const Vec3f a = s.bounds_min(), b = s.bounds_max();
            return std::make_tuple(std::array<float, 3>{a.x, a.y, a.z}, std::array<float, 3>{b.x, b.y, b.z});
        })
        .def("intersect", [](const Scene& s, std::array<float, 3> o, std::array<float, 3> d) -> nb::object {
            Hit h;
            if (!s.intersect_checked(vec(o), vec(d), h)) return nb::none();
            return nb::make_tuple(h.t, std::array<float, 3>{h.p.x, h.p.y, h.p.z}, h.tri);
        }, "o"_a, "d"_a, "Nearest hit (t, point, triangle) along o + t d, or None.");

    m.def("_build_scene", [](const std::string& name, Scene& scene, int width, int height, float albedo,
                              float emission) {
        nb::gil_scoped_release release;
        return build_scene(name, scene, width, height, albedo, emission);
    });

    m.def("_trace_photons", [](const Scene& scene, std::uint64_t count, std::uint64_t seed, unsigned threads,
                               std::uint64_t max_stored) {
        TraceStats st;
        std::vector<Photon> ph;
        {
            nb::gil_scoped_release release;
            ph = trace_photons(scene, count, seed, threads, &st, 0, max_stored);
        }
        nb::dict d;
        d["position"] = photons_field(ph, 0);
        d["power"] = photons_field(ph, 1);
        d["normal"] = photons_field(ph, 2);
        d["emitted"] = st.emitted;
        d["emitted_power"] = std::array<float, 3>{st.emitted_power.x, st.emitted_power.y, st.emitted_power.z};
        d["stored"] = st.stored;
        return d;
    }, "scene"_a, "count"_a, "seed"_a = 0, "threads"_a = 0, "max_stored"_a = kDefaultStoredPhotonBudget);

    nb::class_<PhotonMap>(m, "PhotonMap",
                          "A photon map over positions (N, 3) float32: grid='adaptive' (density-sized cells culled against the sphere), 'hash' (VR-photon-mapping) or 'kdtree' (Jensen).")
        .def("__init__", [](PhotonMap* pm, const FloatArray& positions, float radius, const std::string& grid,
                            const std::string& mode) {
            std::vector<Photon> ph = photons_from(positions);
            const GridKind kind = parse_grid_kind(grid);
            const HashGrid::Mode md = parse_hash_mode(mode);
            nb::gil_scoped_release release;
            new (pm) PhotonMap(ph, radius, kind, md);
        }, "positions"_a, "radius"_a, "grid"_a = "hash", "hash_mode"_a = "auto")
        .def_prop_ro("size", &PhotonMap::size)
        .def_prop_ro("dense", [](const PhotonMap& pm) { return pm.grid() && pm.grid()->dense(); },
                     "True for the dense hash grid, False for the hashed fallback or the kd-tree.")
        .def_prop_ro("cell_count", [](const PhotonMap& pm) { return pm.grid() ? pm.grid()->cell_count() : 0; })
        .def("query_radius", [](const PhotonMap& pm, std::array<float, 3> q, float r) {
            const auto idx = pm.query_radius(vec(q), r);
            std::vector<float> v;
            for (auto i : idx) { const Vec3f p = pm.photons()[i].p; v.insert(v.end(), {p.x, p.y, p.z}); }
            return to_numpy(std::move(v), {idx.size(), 3});
        }, "point"_a, "radius"_a, "Positions of every photon within radius (at most the map's radius).")
        .def("query_knn", [](const PhotonMap& pm, std::array<float, 3> q, int k, float r) {
            const auto idx = pm.query_knn(vec(q), k, r);
            std::vector<float> v;
            for (auto i : idx) { const Vec3f p = pm.photons()[i].p; v.insert(v.end(), {p.x, p.y, p.z}); }
            return to_numpy(std::move(v), {idx.size(), 3});
        }, "point"_a, "k"_a, "radius"_a, "Positions of the k nearest photons within radius, nearest first.");

    m.def("_render", [](const Scene& scene, const Camera& cam, std::uint64_t photons, float radius,
                        const std::string& grid, const std::string& gather, int k, const std::string& kernel,
                        int spp, int light_samples, std::uint64_t seed, const std::string& pipeline,
                        bool cooperative, bool direct, bool indirect, unsigned threads, const std::string& mode,
                        bool disc) {
        const RenderSettings s = make_settings(photons, radius, grid, gather, k, kernel, spp, light_samples, seed,
                                               pipeline, cooperative, direct, indirect, threads, mode, disc);
        require_render_size(cam);
        RenderStats st;
        std::vector<float> img;
        {
            nb::gil_scoped_release release;
            Renderer r(scene, s);
            img = r.render(cam, st);
        }
        return nb::make_tuple(to_numpy(std::move(img), {std::size_t(cam.height), std::size_t(cam.width), 3}),
                              stats_dict(st));
    }, "scene"_a, "camera"_a, RENDER_ARGS);

    m.def("_render_progressive", [](const Scene& scene, const Camera& cam, std::uint64_t photons, float radius,
                                    const std::string& grid, const std::string& gather, int k,
                                    const std::string& kernel, int spp, int light_samples, std::uint64_t seed,
                                    const std::string& pipeline, bool cooperative, bool direct, bool indirect,
                                    unsigned threads, const std::string& mode, bool disc, int passes, double time_budget,
                                    float alpha, const std::vector<int>& snapshots, bool final_gather,
                                    int coarse_passes) {
        const RenderSettings s = make_settings(photons, radius, grid, gather, k, kernel, spp, light_samples, seed,
                                               pipeline, cooperative, direct, indirect, threads, mode, disc);
        ProgressiveSettings p;
        p.passes = passes;
        p.time_budget = time_budget;
        p.alpha = alpha;
        p.final_gather = final_gather;
        p.coarse_passes = coarse_passes;
        p.validate();
        ProgressiveStats st;
        std::vector<float> img;
        struct Snapshot {
            int passes;
            double seconds;
            std::vector<float> image;
        };
        std::vector<Snapshot> shots;
        {
            nb::gil_scoped_release release;
            PassCallback keep;
            if (!snapshots.empty())
                keep = [&](int done, const std::vector<float>& image, double seconds) {
                    if (std::find(snapshots.begin(), snapshots.end(), done) != snapshots.end())
                        shots.push_back({done, seconds, image});
                };
            img = render_progressive(scene, cam, s, p, st, keep);
        }
        const std::size_t h = std::size_t(cam.height), w = std::size_t(cam.width);
        nb::dict d = stats_dict(st.render);
        d["passes"] = st.passes;
        d["mean_radius"] = st.mean_radius;
        nb::list l;
        for (auto& shot : shots)
            l.append(nb::make_tuple(shot.passes, shot.seconds, to_numpy(std::move(shot.image), {h, w, 3})));
        d["snapshots"] = l;
        return nb::make_tuple(to_numpy(std::move(img), {h, w, 3}), d);
    }, "scene"_a, "camera"_a, RENDER_ARGS, "passes"_a = 16, "time_budget"_a = 0.0, "alpha"_a = 2.0f / 3.0f,
       "snapshots"_a = std::vector<int>{}, "final_gather"_a = false,
       "coarse_passes"_a = ProgressiveSettings{}.coarse_passes);

    m.def("_render_stereo", [](const Scene& scene, const StereoCamera& eyes, bool reuse, std::uint64_t photons,
                               float radius, const std::string& grid, const std::string& gather, int k,
                               const std::string& kernel, int spp, int light_samples, std::uint64_t seed,
                               const std::string& pipeline, bool cooperative, bool direct, bool indirect,
                               unsigned threads, const std::string& mode, bool disc) {
        const RenderSettings s = make_settings(photons, radius, grid, gather, k, kernel, spp, light_samples, seed,
                                               pipeline, cooperative, direct, indirect, threads, mode, disc);
        require_render_size(eyes.left, 2 * 12);
        StereoImages out;
        {
            nb::gil_scoped_release release;
            Renderer r(scene, s);
            out = render_stereo(r, eyes, reuse);
        }
        const std::size_t h = std::size_t(eyes.left.height), w = std::size_t(eyes.left.width);
        nb::dict d;
        d["left"] = stats_dict(out.left_stats);
        d["right"] = stats_dict(out.right_stats);
        d["total_seconds"] = out.total_seconds;
        d["reused_pixels"] = out.right_stats.reused_pixels;
        d["reused_share"] = double(out.right_stats.reused_pixels) / double(h * w);
        return nb::make_tuple(to_numpy(std::move(out.left), {h, w, 3}), to_numpy(std::move(out.right), {h, w, 3}), d);
    }, "scene"_a, "eyes"_a, "reuse"_a, RENDER_ARGS);
}
}  // namespace gigascroll::bindings
