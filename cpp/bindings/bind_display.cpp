// display/: the full-resolution display pass (DisplayPass), its lighting interface and the
// bare primary-ray cast it is measured against.
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <cmath>

#include "bindings/arrays.h"
#include "bindings/bindings.h"
#include "common/error.h"
#include "display/display_pass.h"
#include "views/exhibition.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {

nb::dict eye_stats(const EyeStats& s) {
    nb::dict d;
    d["rays_seconds"] = s.rays_seconds, d["reuse_seconds"] = s.reuse_seconds;
    d["vt_seconds"] = s.vt_seconds, d["shade_seconds"] = s.shade_seconds;
    d["total_seconds"] = s.total_seconds();
    d["pixels"] = s.pixels, d["hits"] = s.hits, d["traced"] = s.traced, d["reused"] = s.reused;
    d["painting_pixels"] = s.painting_pixels;
    return d;
}

DisplayOptions display_options(bool srgb_albedo, float edge_depth_ratio, float lod_bias,
                               unsigned threads) {
    require(std::isfinite(lod_bias), "lod_bias must be finite");
    DisplayOptions o;
    o.srgb_albedo = srgb_albedo, o.edge_depth_ratio = edge_depth_ratio;
    o.lod_bias = lod_bias, o.threads = threads;
    return o;
}

using Image = nb::ndarray<nb::numpy, float, nb::ndim<3>>;

// The display pass over any scene that yields a PaintingSceneView (the ExhibitionScene here;
// the Gallery's binding adds its own overloads through bind_display_scene).
void bind_display_pass(nb::module_& m) {
    nb::class_<DisplayLighting>(m, "DisplayLighting",
        "What the display pass multiplies the albedo by: irradiance, room albedo, emission.");
    nb::class_<UnlitLighting, DisplayLighting>(m, "UnlitLighting",
        "Radiance = albedo (irradiance pi everywhere); surfaces other than paintings grey.")
        .def("__init__", [](UnlitLighting* self, std::array<float, 3> a) {
            for (float c : a) require(std::isfinite(c) && c >= 0 && c <= 1, "UnlitLighting: albedo in [0, 1]");
            new (self) UnlitLighting(Vec3f{a[0], a[1], a[2]}); }, "occluder_albedo"_a = std::array<float, 3>{0.5f, 0.5f, 0.5f});

    nb::class_<DisplayPass>(m, "DisplayPass",
        "The full-resolution display pass: primary rays, trilinear VT albedo at the pixel's\n"
        "level of detail, times the lighting; render_stereo reuses the left eye's hits in the\n"
        "right eye (VR-photon-mapping §3.3). Keeps its buffers between frames; not reentrant.")
        .def(nb::init<>())
        .def("render", [](DisplayPass& d, const ExhibitionScene& scene, const DisplayLighting& lighting,
                          const VirtualTexture& vt, const Camera& eye, bool srgb_albedo,
                          float lod_bias, unsigned threads) {
            require(scene.committed(), "commit() the scene before the display pass");
            FreshArray<float, nb::ndim<3>> out({eye.height, eye.width, 3});
            const DisplayOptions o = display_options(srgb_albedo, 0.05f, lod_bias, threads);
            {
                nb::gil_scoped_release release;
                d.render(scene.view(), lighting, vt, eye, o, out.data);
            }
            return out.array; },
            "scene"_a, "lighting"_a, "vt"_a, "eye"_a, "srgb_albedo"_a = true, "lod_bias"_a = 0.0f,
            "threads"_a = 0, "One eye: (height, width, 3) float32 linear radiance.")
        .def("render_stereo", [](DisplayPass& d, const ExhibitionScene& scene, const DisplayLighting& lighting,
                                 const VirtualTexture& vt, const Camera& left, const Camera& right,
                                 bool reuse, bool srgb_albedo, float edge_depth_ratio, float lod_bias,
                                 float reuse_lod_tolerance, unsigned threads) {
            require(scene.committed(), "commit() the scene before the display pass");
            FreshArray<float, nb::ndim<3>> l({left.height, left.width, 3});
            FreshArray<float, nb::ndim<3>> r({right.height, right.width, 3});
            DisplayOptions o = display_options(srgb_albedo, edge_depth_ratio, lod_bias, threads);
            o.reuse_lod_tolerance = reuse_lod_tolerance;
            {
                nb::gil_scoped_release release;
                d.render_stereo(scene.view(), lighting, vt, left, right, reuse, o, l.data, r.data);
            }
            return nb::make_tuple(l.array, r.array); },
            "scene"_a, "lighting"_a, "vt"_a, "left"_a, "right"_a, "reuse"_a = true,
            "srgb_albedo"_a = true, "edge_depth_ratio"_a = 0.05f, "lod_bias"_a = 0.0f,
            "reuse_lod_tolerance"_a = DisplayOptions{}.reuse_lod_tolerance, "threads"_a = 0,
            "Both eyes: (left, right) float32 images; reuse=False traces the right eye in full.\n"
            "A reused right pixel keeps the left eye's texel where its level of detail is within\n"
            "reuse_lod_tolerance of the left eye's (0: it always samples its own).")
        // The accessors wait for a render under way in another thread: without the GIL.
        .def_prop_ro("left_stats", [](const DisplayPass& d) {
            return eye_stats(without_gil([&] { return d.left_stats(); })); })
        .def_prop_ro("right_stats", [](const DisplayPass& d) {
            return eye_stats(without_gil([&] { return d.right_stats(); })); })
        .def("reuse_sources", [](const DisplayPass& d) {
            return to_numpy(without_gil([&] { return d.reuse_sources(); })); },
            "Per right pixel (flat), the left pixel whose hit it reuses (-1: traced).")
        .def("hit_points", [](const DisplayPass& d, int eye) {
            return to_numpy(without_gil([&] { return d.hit_points(eye); })); },
             "eye"_a, "Flat (x, y, z) per pixel of eye 0 (left) or 1 (right); NaN where no hit.")
        .def("lods", [](const DisplayPass& d, int eye) {
            return to_numpy(without_gil([&] { return d.lods(eye); })); },
             "eye"_a, "Flat level of detail per pixel (NaN off paintings).");

    m.def("cast_primary_rays", [](const ExhibitionScene& scene, const Camera& eye, unsigned threads) {
        require(scene.committed(), "commit() the scene first");
        std::uint64_t hits = 0;
        double s;
        {
            nb::gil_scoped_release release;
            s = cast_primary_rays(scene.handle(), eye, threads, &hits);
        }
        return nb::make_tuple(s, hits); }, "scene"_a, "eye"_a, "threads"_a = 0,
        "The display's baseline: the same primary rays, nothing done at the hits: (seconds, hits).");
}

}  // namespace

void bind_display(nb::module_& m) { bind_display_pass(m); }

}  // namespace gigascroll::bindings
