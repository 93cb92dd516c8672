// gallery/: the one scene of room and paintings, its lighting and its display pass.
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include "bindings/arrays.h"
#include "bindings/bindings.h"
#include "common/error.h"
#include "gallery/display_lighting.h"
#include "gallery/gallery.h"
#include "pack/reader.h"
#include "display/display_pass.h"
#include "views/feedback.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {

using FloatArray = nb::ndarray<const float, nb::c_contig, nb::device::cpu>;
using IndexArray = nb::ndarray<const std::int64_t, nb::c_contig, nb::device::cpu>;
using ImageOut = nb::ndarray<float, nb::ndim<3>, nb::c_contig, nb::device::cpu>;

using AnyArray = nb::ndarray<nb::device::cpu>;

// The caller's image (checked by the core) or a fresh one: (the array to return, its floats).
std::pair<nb::object, float*> output_image(const nb::object& out, const Camera& eye,
                                           const char* what) {
    if (out.is_none()) {
        FreshArray<float, nb::ndim<3>> fresh({eye.height, eye.width, 3});
        return {nb::cast(fresh.array), fresh.data};
    }
    AnyArray a;
    OutputImage image;
    std::int64_t shape[3] = {0, 0, 0}, strides[3] = {0, 0, 0};
    if (nb::try_cast(out, a, false)) {
        image.ndim = a.ndim();
        for (std::size_t i = 0; i < image.ndim && i < 3; ++i) shape[i] = a.shape(i), strides[i] = a.stride(i);
        image.data = a.data(), image.shape = shape, image.strides = strides;
        image.float32 = a.dtype() == nb::dtype<float>();
        // A read-only numpy array (nanobind hands its data to a non-const view regardless).
        image.writable = !nb::hasattr(out, "flags") || nb::cast<bool>(out.attr("flags").attr("writeable"));
    }
    return {out, check_output_image(image, eye, what)};
}

Vec3d vec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
Vec3f vec3f(const std::array<float, 3>& a) { return {a[0], a[1], a[2]}; }

}  // namespace

void bind_gallery(nb::module_& m) {
    nb::class_<Gallery>(m, "_Gallery",
        "The room and its paintings in one Embree scene (see gigascroll.Gallery).")
        .def(nb::init<>())
        .def("_add_surface", [](Gallery& g, const FloatArray& v, const IndexArray& t,
                                std::array<float, 3> albedo, std::array<float, 3> emission) {
            require(v.ndim() == 2 && v.shape(1) == 3, "Gallery: vertices must have shape (N, 3)");
            require(t.ndim() == 2 && t.shape(1) == 3, "Gallery: triangles must have shape (M, 3)");
            return g.add_surface(v.data(), v.shape(0), t.data(), t.shape(0), vec3f(albedo), vec3f(emission));
        }, "vertices"_a, "triangles"_a, "albedo"_a, "emission"_a)
        .def("_add_painting", [](Gallery& g, const TilePack& pack, std::int64_t painting,
                                 std::array<double, 3> origin, std::array<double, 3> u_axis,
                                 std::array<double, 3> v_axis, double width_m, double height_m) {
            const PackGeometry layout = pack.geometry();
            require(painting >= 0 && std::size_t(painting) < layout.paintings.size(),
                    "Gallery: painting index " + std::to_string(painting) + " is not in the pack");
            return g.add_painting(std::uint32_t(painting), layout.paintings[painting], vec3(origin),
                                  vec3(u_axis), vec3(v_axis), width_m, height_m);
        }, "pack"_a, "painting"_a, "origin"_a, "u_axis"_a, "v_axis"_a, "width_m"_a, "height_m"_a)
        .def("_commit", [](Gallery& g) {
            nb::gil_scoped_release release;
            g.commit();
        })
        .def_prop_ro("committed", &Gallery::committed)
        .def_prop_ro("lit", &Gallery::lit)
        .def_prop_ro("baked", &Gallery::baked)
        .def_prop_ro("triangle_count", [](const Gallery& g) { return g.scene().triangle_count(); })
        .def_prop_ro("emitter_count", [](const Gallery& g) { return g.scene().emitter_count(); })
        .def_prop_ro("painting_count", [](const Gallery& g) { return g.paintings().size(); })
        .def_prop_ro("origin", [](const Gallery& g) {
            const Vec3d o = g.origin();
            return std::array<double, 3>{o.x, o.y, o.z};
        }, "Where the room's own coordinates (the BVH's, the bake's triangle frames) have their "
           "origin in the world: (0, 0, 0) unless the room lies far from the world's origin.")
        .def_prop_ro("bounds", [](const Gallery& g) {
            const auto [a, b] = g.bounds();
            return std::make_tuple(std::array<float, 3>{float(a.x), float(a.y), float(a.z)},
                                   std::array<float, 3>{float(b.x), float(b.y), float(b.z)});
        })
        .def("_light", [](Gallery& g, const VirtualTexture& vt, std::uint64_t photons, float radius,
                          int light_samples, std::uint64_t seed, unsigned threads, bool disc,
                          bool indirect) {
            LightingSettings s{photons, radius, light_samples, seed, threads, disc, indirect};
            nb::gil_scoped_release release;
            g.light(vt, s);
        }, "vt"_a, "photons"_a, "radius"_a, "light_samples"_a, "seed"_a, "threads"_a, "disc"_a,
           "indirect"_a = true)
        .def("_bake", [](Gallery& g, double spacing, int light_samples, unsigned threads, bool stratified,
                         bool skip_unlit, int gather_stride, bool inset_edges, bool coarse_disc,
                         bool analytic_direct, int shadow_probes, bool fill_covered, float indirect_filter,
                         int final_gather, bool sparse_final_gather, float hot_spots) {
            BakeSettings s;
            s.spacing = spacing, s.light_samples = light_samples, s.threads = threads;
            s.stratified = stratified, s.skip_unlit = skip_unlit, s.gather_stride = gather_stride;
            s.inset_edges = inset_edges, s.coarse_disc = coarse_disc, s.analytic_direct = analytic_direct;
            s.shadow_probes = shadow_probes, s.fill_covered = fill_covered, s.indirect_filter = indirect_filter;
            s.final_gather = final_gather, s.sparse_final_gather = sparse_final_gather;
            s.hot_spots = hot_spots;
            nb::gil_scoped_release release;
            g.bake(s);
        }, "spacing"_a, "light_samples"_a, "threads"_a, "stratified"_a = true, "skip_unlit"_a = true,
           "gather_stride"_a = 1, "inset_edges"_a = true,
           "coarse_disc"_a = false, "analytic_direct"_a = true, "shadow_probes"_a = 4,
           "fill_covered"_a = true, "indirect_filter"_a = 0.0f,
           "final_gather"_a = 16, "sparse_final_gather"_a = false, "hot_spots"_a = 8.0f)
        .def("_bake_progress", &Gallery::bake_progress)
        .def("_bake_lattice", [](const Gallery& g) {
            // Copies of the bake's lattices and the triangles' frames, taken under the read
            // lock (light() and bake() replace them), for exporting the bake as a mesh.
            require(g.baked(), "Gallery: bake() first");
            const std::size_t T = g.scene().triangle_count();
            std::size_t P = 0;
            {
                const auto lock = g.read_lock();
                P = g.bake_arrays().points;
            }
            FreshArray<std::uint32_t> segments({T}), geometry({T});
            FreshArray<std::uint64_t> offset({T});
            FreshArray<std::int32_t> slot({T});
            FreshArray<float> v0({T, 3}), e1({T, 3}), e2({T, 3}), albedo({T, 3}), emission({T, 3});
            FreshArray<float> front({P, 3}), back({P, 3});
            {
                nb::gil_scoped_release release;
                const auto lock = g.read_lock();
                const Gallery::BakeArrays b = g.bake_arrays();
                const Gallery::TriangleFrames f = g.triangle_frames();
                require(b.points == P && f.count == T, "Gallery: the bake changed while it was read");
                const Scene& sc = g.scene();
                const std::uint32_t* first = sc.geometry_first_triangles();
                std::uint32_t geom = 0;
                for (std::size_t t = 0; t < T; ++t) {
                    while (geom + 1 < sc.geometry_count() && first[geom + 1] <= t) ++geom;
                    segments.data[t] = b.segments[t], offset.data[t] = b.offset[t];
                    geometry.data[t] = geom, slot.data[t] = g.slot_of(std::uint32_t(t));
                    const Vec3f a = sc.albedo(std::uint32_t(t)), e = sc.emission(std::uint32_t(t));
                    const Vec3f* rows[5] = {&f.v0[t], &f.e1[t], &f.e2[t], &a, &e};
                    float* outs[5] = {v0.data, e1.data, e2.data, albedo.data, emission.data};
                    for (int k = 0; k < 5; ++k)
                        outs[k][3 * t] = rows[k]->x, outs[k][3 * t + 1] = rows[k]->y, outs[k][3 * t + 2] = rows[k]->z;
                }
                for (std::size_t k = 0; k < P; ++k) {
                    front.data[3 * k] = b.front[k].x, front.data[3 * k + 1] = b.front[k].y, front.data[3 * k + 2] = b.front[k].z;
                    back.data[3 * k] = b.back[k].x, back.data[3 * k + 1] = b.back[k].y, back.data[3 * k + 2] = b.back[k].z;
                }
            }
            nb::dict d;
            d["segments"] = segments.array, d["offset"] = offset.array, d["front"] = front.array;
            d["back"] = back.array, d["v0"] = v0.array, d["e1"] = e1.array, d["e2"] = e2.array;
            d["slot"] = slot.array, d["geometry"] = geometry.array, d["albedo"] = albedo.array;
            d["emission"] = emission.array;
            const Vec3d o = g.origin();
            d["origin"] = std::array<double, 3>{o.x, o.y, o.z};
            return d;
        }, "The bake's lattices and the triangles' frames (relative to origin, the world "
           "position the room is held around), albedo, emission, painting slot (-1: room "
           "surface) and geometry (one per add_surface / add_painting that kept a triangle), "
           "copied under the read lock.")
        .def_prop_ro("stats", [](const Gallery& g) {
            const LightingStats& s = g.stats();
            nb::dict d;
            d["photon_seconds"] = s.photon_seconds;
            d["build_seconds"] = s.build_seconds;
            d["bake_seconds"] = s.bake_seconds;
            d["photons_stored"] = s.photons_stored;
            d["bake_points"] = s.bake_points;
            d["bake_sides_skipped"] = s.bake_sides_skipped;
            d["bake_points_covered"] = s.bake_points_covered;
            d["bake_hot_points"] = s.bake_hot_points;
            d["radius"] = s.radius;
            d["spacing"] = s.spacing;
            d["albedo_levels"] = s.albedo_levels;
            return d;
        }, "Timings and sizes of the last light() and bake().")
        .def("_render_display", [](const Gallery& g, const Camera& camera, const VirtualTexture& vt,
                                   const std::string& lighting, ImageOut out, bool hits, unsigned threads,
                                   bool reference) {
            const Lighting l = parse_lighting(lighting);
            const std::size_t W = camera.width, H = camera.height;
            require(out.shape(0) == H && out.shape(1) == W && out.shape(2) == 3,
                    "render_display: out must have shape (" + std::to_string(H) + ", " +
                        std::to_string(W) + ", 3) float32");
            nb::dict d;
            DisplayHits h;
            if (hits) {
                FreshArray<float> position({H, W, 3});
                FreshArray<std::int32_t> slot({H, W});
                FreshArray<double> uv({H, W, 2});
                FreshArray<float> lod({H, W});
                FreshArray<float> irradiance({H, W, 3});
                h = {position.data, slot.data, uv.data, lod.data, irradiance.data};
                d["irradiance"] = irradiance.array;
                d["position"] = position.array;
                d["slot"] = slot.array;
                d["uv"] = uv.array;
                d["lod"] = lod.array;
            }
            {
                nb::gil_scoped_release release;
                g.render_display(camera, vt, l, out.data(), h, threads, reference);
            }
            return d;
        }, "camera"_a, "vt"_a, "lighting"_a, "out"_a, "hits"_a, "threads"_a, "reference"_a = false)
        .def("render_view", [](const Gallery& g, const Camera& camera, std::int64_t width,
                               std::int64_t height, double lod_bias, unsigned threads,
                               std::int64_t display_step) {
            const FeedbackOptions o = checked_feedback_options(width, height, lod_bias, threads, display_step);
            const FeedbackShape s = feedback_shape(camera, o);
            FreshArray<std::uint64_t> keys({s.height, s.width});
            FreshArray<float> lod({s.display_height, s.display_width});
            FreshArray<double> uv({s.display_height, s.display_width, 2});
            const PaintingSceneView view = g.feedback_view();
            {
                nb::gil_scoped_release release;
                render_view(view, camera, o, keys.data, lod.data, uv.data);
            }
            nb::dict d;
            d["keys"] = keys.array;
            d["display_step"] = display_step;
            d["lod"] = lod.array;
            d["uv"] = uv.array;
            return d;
        }, "camera"_a, "width"_a = 0, "height"_a = 0, "lod_bias"_a = 0.0, "threads"_a = 0,
           "display_step"_a = 1,
           "The feedback pass on the gallery's scene (same outputs as gigascroll.render_view).")
        .def("intersect", [](const Gallery& g, std::array<double, 3> o, std::array<float, 3> d) -> nb::object {
            Hit h;
            if (!g.intersect(vec3(o), vec3f(d), h)) return nb::none();
            return nb::make_tuple(h.t, std::array<float, 3>{h.p.x, h.p.y, h.p.z}, h.tri, g.slot_of(h.tri));
        }, "o"_a, "d"_a, "Nearest hit (t, point, triangle, painting slot or -1) along o + t d, or None.");

    // A bake's lattice points at most (BakeSettings::max_points): a room's triangle budget.
    m.attr("BAKE_MAX_POINTS") = BakeSettings{}.max_points;

    // The full-resolution display pass (display/display_pass.h) on the gallery's scene and
    // light, one eye or a stereo pair with the right eye reusing the left eye's hits.
    // out / out_left, out_right: arrays the caller keeps between frames (None: fresh ones).
    m.def("_gallery_display", [](DisplayPass& d, const Gallery& g, const VirtualTexture& vt,
                                 const Camera& eye, const std::string& lighting, unsigned threads,
                                 nb::object out) {
        auto [array, rgb] = output_image(out, eye, "display: out");
        {
            nb::gil_scoped_release release;
            const GalleryLighting light(g, parse_lighting(lighting));
            d.render(g.feedback_view(), light, vt, eye, GalleryLighting::options(threads), rgb);
        }
        return array;
    }, "display"_a, "gallery"_a, "vt"_a, "eye"_a, "lighting"_a, "threads"_a = 0,
       "out"_a.noconvert() = nb::none());
    m.def("_gallery_display_stereo", [](DisplayPass& d, const Gallery& g, const VirtualTexture& vt,
                                        const Camera& left, const Camera& right,
                                        const std::string& lighting, bool reuse,
                                        float edge_depth_ratio, unsigned threads,
                                        nb::object out_left,
                                        nb::object out_right) {
        auto [l, l_rgb] = output_image(out_left, left, "display: out_left");
        auto [r, r_rgb] = output_image(out_right, right, "display: out_right");
        check_disjoint_images(l_rgb, r_rgb, std::size_t(left.width) * left.height * 3);
        require(std::isfinite(edge_depth_ratio) && edge_depth_ratio >= 0,
                "display: edge_depth_ratio must be finite and >= 0");
        {
            nb::gil_scoped_release release;
            const GalleryLighting light(g, parse_lighting(lighting));
            DisplayOptions o = GalleryLighting::options(threads);
            o.edge_depth_ratio = edge_depth_ratio;
            d.render_stereo(g.feedback_view(), light, vt, left, right, reuse, o, l_rgb, r_rgb);
        }
        return nb::make_tuple(l, r);
    }, "display"_a, "gallery"_a, "vt"_a, "left"_a, "right"_a, "lighting"_a, "reuse"_a = true,
       "edge_depth_ratio"_a = 0.05f, "threads"_a = 0, "out_left"_a.noconvert() = nb::none(),
       "out_right"_a.noconvert() = nb::none());
    m.def("_gallery_primary_rays", [](const Gallery& g, const Camera& eye, unsigned threads) {
        std::uint64_t hits = 0;
        double s;
        {
            nb::gil_scoped_release release;
            s = cast_primary_rays(g.feedback_view().handle, eye.moved(-g.origin()), threads, &hits);
        }
        return nb::make_tuple(s, hits);
    }, "gallery"_a, "eye"_a, "threads"_a = 0);
}

}  // namespace gigascroll::bindings
