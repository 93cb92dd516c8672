// sampling/: software virtual-texture sampling, the plain mip texture and the sparse display.
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
