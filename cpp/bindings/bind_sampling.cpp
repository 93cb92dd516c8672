// sampling/: software virtual-texture sampling, the plain mip texture and the display pass.
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <cstring>
#include <string>

#include "bindings/arrays.h"
#include "bindings/bindings.h"
#include "common/error.h"

#include "pack/reader.h"
#include "sampling/display.h"
#include "sampling/foveation.h"
#include "sampling/mip_texture.h"
#include "sampling/sampler.h"
#include "sampling/stereo_display.h"
#include "views/exhibition.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {
using Coords = nb::ndarray<const double, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Lods = nb::ndarray<const float, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
using Values = nb::ndarray<float, nb::ndim<2>, nb::c_contig, nb::device::cpu>;
using Levels = nb::ndarray<std::int8_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
// Fills a SampleRequest from the arrays (nanobind checked dtype and contiguity), checking sizes.
SampleRequest sample_request(std::uint32_t painting, const Coords& u, const Coords& v,
                             const std::optional<Lods>& lod, float lod_scalar,
                             const std::string& filter, Values& out, Levels& levels,
                             unsigned threads) {
    const std::size_t n = u.shape(0);
    require(v.shape(0) == n, "u and v must have the same length");
    require(out.shape(0) == n && out.shape(1) == 3, "out must be an (n, 3) float32 array");
    require(levels.shape(0) == n, "levels must be an (n,) int8 array");
    SampleRequest r;
    r.painting = painting;
    r.u = u.data();
    r.v = v.data();
    if (lod) {
        require(lod->shape(0) == n, "lod must be an array of length n");
        r.lod = lod->data();
    }
    r.lod_scalar = lod_scalar;
    r.count = n;
    r.filter = parse_filter(filter);
    r.out = out.data();
    r.level_out = levels.data();
    r.threads = threads;
    return r;
}


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
void bind_stereo_display(nb::module_& m) {
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

void bind_sampling(nb::module_& m) {
    m.def("_sample_into", [](const VirtualTexture& vt, std::uint32_t painting, const Coords& u,
                                const Coords& v, const std::optional<Lods>& lod, float lod_scalar,
                                const std::string& filter, Values out, Levels levels, unsigned threads) {
            const SampleRequest r = sample_request(painting, u, v, lod, lod_scalar, filter, out, levels, threads);
            nb::gil_scoped_release release;
            sample(vt, r); },
            "vt"_a, "painting"_a, "u"_a, "v"_a, "lod"_a.none(), "lod_scalar"_a, "filter"_a,
            "out"_a.noconvert(), "levels"_a.noconvert(), "threads"_a);

    nb::class_<MipTexture>(m, "MipTexture",
        "A plain in-memory mip-mapped texture sampled by the same filter code (the baseline).")
        .def("__init__", [](MipTexture* self, const TilePack& pack, std::uint32_t painting, std::uint32_t levels) {
            nb::gil_scoped_release release;
            new (self) MipTexture(MipTexture::from_pack(pack, painting, levels)); },
            "pack"_a, "painting"_a = 0, "levels"_a = 0,
            "Assembles levels [0, levels) of a painting from the pack's tiles (0 = all).")
        .def_prop_ro("levels", &MipTexture::level_count)
        .def("level", [](const MipTexture& t, std::uint32_t l) {
            require(l < t.level_count(), "level out of range");
            const auto& lv = t.level(l);
            return nb::ndarray<nb::numpy, const std::uint8_t, nb::ndim<3>>(
                lv.rgb.data(), {lv.height, lv.width, 3}, nb::handle()); },
            nb::rv_policy::reference_internal, "level"_a);

    m.def("_sample_into", [](const MipTexture& t, const Coords& u, const Coords& v,
                                const std::optional<Lods>& lod, float lod_scalar,
                                const std::string& filter, Values out, Levels levels, unsigned threads) {
            const SampleRequest r = sample_request(0, u, v, lod, lod_scalar, filter, out, levels, threads);
            nb::gil_scoped_release release;
            t.sample(r); },
            "texture"_a, "u"_a, "v"_a, "lod"_a.none(), "lod_scalar"_a, "filter"_a, "out"_a.noconvert(), "levels"_a.noconvert(), "threads"_a);

    m.def("display_view", [](const VirtualTexture& vt,
                             nb::ndarray<const std::uint64_t, nb::ndim<2>, nb::c_contig> keys,
                             nb::ndarray<const float, nb::ndim<2>, nb::c_contig> lod,
                             nb::ndarray<const double, nb::ndim<3>, nb::c_contig> uv,
                             std::uint32_t step, unsigned threads) {
        require(step >= 1, "display step must be >= 1");
        const std::size_t h = keys.shape(0), w = keys.shape(1);
        const std::size_t oh = display_extent(std::uint32_t(h), step),
                          ow = display_extent(std::uint32_t(w), step);
        require(lod.shape(0) == oh && lod.shape(1) == ow && uv.shape(0) == oh &&
                    uv.shape(1) == ow && uv.shape(2) == 2,
                "display_view: keys (h, w) need lod (h', w') and uv (h', w', 2) on the display "
                "grid, h' = ceil(h / step) (render_view(..., display_step=step))");
        FreshArray<float> out({oh, ow, 3});
        {
            nb::gil_scoped_release release;
            display_view(vt, keys.data(), lod.data(), uv.data(), std::uint32_t(w),
                         std::uint32_t(h), step, out.data, threads);
        }
        return out.array;
    }, "vt"_a, "keys"_a, "lod"_a, "uv"_a, "step"_a = 1, "threads"_a = 0,
          "The display pass: samples every step-th pixel per axis of a view through the\n"
          "virtual texture (bilinear at round(lod)), from render_view(..., display_step=step);\n"
          "(h', w', 3) float32, black where no painting is seen.");

    bind_stereo_display(m);

    using Image = nb::ndarray<const float, nb::ndim<3>, nb::c_contig, nb::device::cpu>;
    using Weights = nb::ndarray<const float, nb::ndim<1>, nb::c_contig, nb::device::cpu>;
    m.def("_composite_foveated", [](const Image& periphery, const Image& fovea,
                                    const Weights& weight_x, const Weights& weight_y,
                                    std::uint32_t x0, std::uint32_t y0, std::uint32_t factor,
                                    std::uint32_t width, std::uint32_t height, unsigned threads) {
        require(periphery.shape(2) == 3 && fovea.shape(2) == 3,
                "composite_foveated: images must be (h, w, 3)");
        require(weight_x.shape(0) == fovea.shape(1) && weight_y.shape(0) == fovea.shape(0),
                "composite_foveated: one weight per fovea column and row");
        require(width > 0 && height > 0 && width <= (1u << 16) && height <= (1u << 16),
                "composite_foveated: eye size out of range");
        const FoveatedEye eye{width, height, factor, std::uint32_t(periphery.shape(1)),
                              std::uint32_t(periphery.shape(0)), x0, y0,
                              std::uint32_t(fovea.shape(1)), std::uint32_t(fovea.shape(0))};
        FreshArray<float, nb::ndim<3>> out({height, width, 3});
        {
            nb::gil_scoped_release release;
            composite_foveated(eye, periphery.data(), fovea.data(), weight_x.data(),
                               weight_y.data(), out.data, threads);
        }
        return out.array;
    }, "periphery"_a, "fovea"_a, "weight_x"_a, "weight_y"_a, "x0"_a, "y0"_a, "factor"_a,
       "width"_a, "height"_a, "threads"_a = 0,
       "A foveated eye (sampling/foveation.h): the periphery upsampled bilinearly by factor,\n"
       "the fovea blended in at (x0, y0) with weight weight_y[y] * weight_x[x].");
}

}  // namespace gigascroll::bindings
