// Python bindings of the views subsystem: exhibition scene, cameras, feedback pass and the
// request-processing methods. Feedback buffers cross as uint64 numpy arrays, without copies.
#include <nanobind/ndarray.h>
#include <nanobind/stl/array.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <array>
#include <cmath>
#include <optional>
#include <string>

#include <type_traits>

#include "bindings/bindings.h"
#include "bindings/numpy_arrays.h"
#include "common/error.h"
#include "vt/display.h"
#include "vt/exhibition.h"
#include "vt/feedback.h"
#include "vt/load_strategy.h"
#include "vt/request.h"
#include "vt/request_hash.h"
#include "vt/request_processing.h"
#include "vt/residency.h"
#include "vt/virtual_texture.h"
#include "vt/vt_lookup.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {

Vec3 vec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
std::array<double, 3> arr3(Vec3 v) { return {v.x, v.y, v.z}; }

// A C-contiguous uint64 array of any shape, viewed as a flat feedback buffer.
struct HeldBuffer {
    nb::ndarray<> array;
    FeedbackBuffer view;
};

HeldBuffer as_buffer(nb::handle h, const char* what) {
    nb::ndarray<> a;
    if (!nb::try_cast(h, a))
        throw InvalidArgument(std::string(what) + " must be a numpy array of uint64 request keys");
    require(a.dtype() == nb::dtype<std::uint64_t>(),
            std::string(what) + " must have dtype uint64 (request keys)");
    require(a.device_type() == nb::device::cpu::value, std::string(what) + " must be on the CPU");
    std::int64_t expect = 1;
    for (std::size_t i = a.ndim(); a.size() > 0 && i-- > 0;) {
        require(a.shape(i) == 1 || a.stride(i) == expect,
                std::string(what) + " must be C-contiguous");
        expect *= std::int64_t(a.shape(i));
    }
    return {a, FeedbackBuffer(static_cast<const std::uint64_t*>(a.data()), a.size())};
}

// Accepts one array or a sequence of arrays (left eye, right eye, magnifier ...).
std::vector<HeldBuffer> as_buffers(nb::handle h) {
    std::vector<HeldBuffer> out;
    nb::ndarray<> probe;
    if (nb::try_cast(h, probe)) {
        out.push_back(as_buffer(h, "feedback buffer"));
        return out;
    }
    if (!nb::isinstance<nb::sequence>(h))
        throw InvalidArgument("feedback buffers must be a uint64 array or a list of them");
    for (nb::handle item : nb::borrow<nb::sequence>(h))
        out.push_back(as_buffer(item, "feedback buffer"));
    return out;
}

std::vector<FeedbackBuffer> views_of(const std::vector<HeldBuffer>& held) {
    std::vector<FeedbackBuffer> v;
    for (const auto& b : held) v.push_back(b.view);
    return v;
}

nb::dict sets_dict(RequestSets&& s) {
    nb::dict d;
    d["requests"] = to_numpy(std::move(s.requests));
    d["responses"] = to_numpy(std::move(s.responses));
    d["commands"] = to_numpy(std::move(s.commands));
    return d;
}

// Runs one frame of a processor on the Python feedback buffers without the GIL. The frame
// number only matters to the hash processor (its salt); the others take it for a common API.
template <typename Processor>
nb::dict process_frame(Processor& p, nb::handle buffers, const ResidencyLookup& lookup,
                       std::uint64_t frame) {
    auto held = as_buffers(buffers);
    auto views = views_of(held);
    RequestSets s;
    {
        nb::gil_scoped_release release;
        if constexpr (std::is_same_v<Processor, HashProcessor>)
            s = p.process(views, lookup, frame);
        else
            s = p.process(views, lookup);
    }
    return sets_dict(std::move(s));
}

std::uint32_t checked_u32(std::int64_t v, std::int64_t hi, const char* what) {
    require(v >= 0 && v <= hi, std::string(what) + " out of range");
    return static_cast<std::uint32_t>(v);
}

}  // namespace

void bind_views(nb::module_& m) {
    m.attr("NO_REQUEST") = kNoRequest;

    nb::class_<PaintingTiles>(m, "PaintingTiles",
                              "Tile pyramid geometry of one painting (levels, tiles per level).")
        .def(nb::init<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>(), "width"_a,
             "height"_a, "tile_size"_a = 128, "border"_a = 4)
        .def_prop_ro("width", &PaintingTiles::width)
        .def_prop_ro("height", &PaintingTiles::height)
        .def_prop_ro("tile_size", &PaintingTiles::tile_size)
        .def_prop_ro("border", &PaintingTiles::border)
        .def_prop_ro("payload", &PaintingTiles::payload)
        .def_prop_ro("levels", &PaintingTiles::levels)
        .def_prop_ro("total_tiles", &PaintingTiles::total_tiles)
        .def_prop_ro("page_table_width", &PaintingTiles::page_table_width)
        .def_prop_ro("page_table_height", &PaintingTiles::page_table_height)
        .def("level_width", &PaintingTiles::level_width)
        .def("level_height", &PaintingTiles::level_height)
        .def("tiles_x", &PaintingTiles::tiles_x)
        .def("tiles_y", &PaintingTiles::tiles_y)
        .def("tile_count", &PaintingTiles::tile_count)
        .def("__repr__", [](const PaintingTiles& p) {
            return "PaintingTiles(" + std::to_string(p.width()) + ", " + std::to_string(p.height()) +
                   ", tile_size=" + std::to_string(p.tile_size()) +
                   ", border=" + std::to_string(p.border()) + ")";
        });

    m.def("pack_request", [](std::int64_t p, std::int64_t l, std::int64_t x, std::int64_t y) {
        return pack_request(checked_u32(p, kMaxPaintings - 1, "painting"),
                            checked_u32(l, kMaxLevels - 1, "level"),
                            checked_u32(x, 65535, "tile x"), checked_u32(y, 65535, "tile y"));
    }, "painting"_a, "level"_a, "x"_a, "y"_a,
          "64-bit request key: painting << 37 | level << 32 | morton(x, y).");
    m.def("unpack_requests", [](nb::handle keys) {
        HeldBuffer b = as_buffer(keys, "keys");
        std::vector<std::uint32_t> p(b.view.size()), l(p.size()), x(p.size()), y(p.size());
        for (std::size_t i = 0; i < p.size(); ++i) {
            const Request r = unpack_request(b.view[i]);
            p[i] = r.painting, l[i] = r.level, x[i] = r.x, y[i] = r.y;
        }
        return nb::make_tuple(to_numpy(std::move(p)), to_numpy(std::move(l)),
                              to_numpy(std::move(x)), to_numpy(std::move(y)));
    }, "keys"_a, "Split request keys into (painting, level, x, y) uint32 arrays (flattened).");

    nb::class_<Camera>(m, "ViewCamera", "A pinhole view: a headset eye or the magnifier.")
        .def("__init__", [](Camera* c, std::array<double, 3> position, std::array<double, 3> forward,
                            std::array<double, 3> up, double tan_half_x, double tan_half_y,
                            std::int64_t width, std::int64_t height) {
            require(width > 0 && height > 0 && width < (1 << 20) && height < (1 << 20),
                    "camera resolution must be positive");
            new (c) Camera(vec3(position), vec3(forward), vec3(up), tan_half_x, tan_half_y,
                           std::uint32_t(width), std::uint32_t(height));
        }, "position"_a, "forward"_a, "up"_a, "tan_half_x"_a, "tan_half_y"_a, "width"_a, "height"_a)
        .def_prop_ro("position", [](const Camera& c) { return arr3(c.position); })
        .def_prop_ro("forward", [](const Camera& c) { return arr3(c.forward); })
        .def_prop_ro("up", [](const Camera& c) { return arr3(c.up); })
        .def_prop_ro("right", [](const Camera& c) { return arr3(c.right); })
        .def_ro("tan_half_x", &Camera::tan_half_x)
        .def_ro("tan_half_y", &Camera::tan_half_y)
        .def_ro("width", &Camera::width)
        .def_ro("height", &Camera::height);

    nb::class_<ExhibitionScene>(m, "ExhibitionScene",
                                "The exhibition room as an Embree scene: paintings, boxes, tables.")
        .def(nb::init<>())
        .def("add_painting", [](ExhibitionScene& s, std::int64_t painting, const PaintingTiles& tiles,
                                std::array<double, 3> origin, std::array<double, 3> u_axis,
                                std::array<double, 3> v_axis, double width_m, double height_m) {
            return s.add_painting(checked_u32(painting, kMaxPaintings - 1, "painting id"), tiles,
                                  vec3(origin), vec3(u_axis), vec3(v_axis), width_m, height_m);
        }, "painting"_a, "tiles"_a, "origin"_a, "u_axis"_a, "v_axis"_a, "width_m"_a, "height_m"_a)
        .def("add_box", [](ExhibitionScene& s, std::array<double, 3> lo, std::array<double, 3> hi) {
            s.add_box(vec3(lo), vec3(hi));
        }, "lo"_a, "hi"_a)
        .def("add_table", &ExhibitionScene::add_table, "x"_a, "z"_a, "length"_a, "depth"_a,
             "height"_a = 0.70)
        .def("commit", &ExhibitionScene::commit)
        .def_prop_ro("committed", &ExhibitionScene::committed)
        .def_prop_ro("box_count", &ExhibitionScene::box_count)
        .def_prop_ro("painting_count", [](const ExhibitionScene& s) { return s.paintings().size(); })
        .def("painting", [](const ExhibitionScene& s, std::size_t i) {
            require(i < s.paintings().size(), "placement index out of range");
            const auto& p = s.paintings()[i];
            nb::dict d;
            d["painting"] = p.painting;
            d["tiles"] = p.tiles;
            d["origin"] = arr3(p.origin);
            d["u_axis"] = arr3(p.u_axis);
            d["v_axis"] = arr3(p.v_axis);
            d["normal"] = arr3(p.normal());
            d["width_m"] = p.width_m;
            d["height_m"] = p.height_m;
            return d;
        }, "index"_a);

    // Deprecated duplicate of render_view (removed once Python no longer uses it).
    m.def("render_feedback", [](const ExhibitionScene& scene, const Camera& camera,
                                std::int64_t width, std::int64_t height, double lod_bias,
                                unsigned threads, bool with_lod) {
        require(width >= 0 && height >= 0 && width < (1 << 16) && height < (1 << 16),
                "feedback resolution out of range");
        FeedbackOptions o{std::uint32_t(width), std::uint32_t(height), lod_bias, threads};
        const std::size_t w = feedback_width(camera, o), h = feedback_height(camera, o);
        std::vector<std::uint64_t> keys(w * h);
        std::vector<float> lod(with_lod ? w * h : 0);
        {
            nb::gil_scoped_release release;
            render_feedback(scene, camera, o, keys.data(), with_lod ? lod.data() : nullptr);
        }
        nb::object keys2d = nb::cast(to_numpy(std::move(keys), {h, w}));
        if (!with_lod) return keys2d;
        return nb::object(nb::make_tuple(keys2d, to_numpy(std::move(lod), {h, w})));
    }, "scene"_a, "camera"_a, "width"_a = 0, "height"_a = 0, "lod_bias"_a = 0.0, "threads"_a = 0,
          "with_lod"_a = false,
          "Feedback pass: (height, width) uint64 request keys (NO_REQUEST where no painting);\n"
          "width/height 0 = 1/8 of the camera's resolution. with_lod also returns lambda.");

    m.def("render_view", [](const ExhibitionScene& scene, const Camera& camera, std::int64_t width,
                            std::int64_t height, double lod_bias, unsigned threads,
                            std::int64_t display_step, bool display) {
        require(width >= 0 && height >= 0 && width < (1 << 16) && height < (1 << 16),
                "view resolution out of range");
        require(display_step >= 1 && display_step < (1 << 16), "display_step must be >= 1");
        FeedbackOptions o{std::uint32_t(width), std::uint32_t(height), lod_bias, threads,
                          std::uint32_t(display_step)};
        const std::size_t w = feedback_width(camera, o), h = feedback_height(camera, o);
        const std::size_t dw = display_extent(std::uint32_t(w), o.display_step),
                          dh = display_extent(std::uint32_t(h), o.display_step);
        FreshArray<std::uint64_t> keys({h, w});
        nb::dict d;
        d["keys"] = keys.array;
        d["display_step"] = display_step;
        if (!display) {
            {
                nb::gil_scoped_release release;
                render_feedback(scene, camera, o, keys.data);
            }
            d["lod"] = nb::none();
            d["uv"] = nb::none();
            return d;
        }
        FreshArray<float> lod({dh, dw});
        FreshArray<double> uv({dh, dw, 2});
        {
            nb::gil_scoped_release release;
            render_feedback(scene, camera, o, keys.data, lod.data, uv.data);
        }
        d["lod"] = lod.array;
        d["uv"] = uv.array;
        return d;
    }, "scene"_a, "camera"_a, "width"_a = 0, "height"_a = 0, "lod_bias"_a = 0.0, "threads"_a = 0,
          "display_step"_a = 1, "display"_a = true,
          "The feedback pass plus what the display pass samples: dict of keys (h, w), and on\n"
          "the display grid (every display_step-th pixel per axis) lod (h', w') and uv\n"
          "(h', w', 2) painting coordinates (NaN where no painting), h' = ceil(h / step).\n"
          "display=False computes the keys only (lod and uv are None).");

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

    m.def("texel_footprint", [](const ExhibitionScene& scene, std::size_t placement,
                                const Camera& camera, double px, double py) {
        require(placement < scene.paintings().size(), "placement index out of range");
        return texel_footprint_at_pixel(scene.paintings()[placement], camera, px, py);
    }, "scene"_a, "placement"_a, "camera"_a, "px"_a, "py"_a,
          "Footprint in level-0 texels of display pixel (px, py) on a painting's plane.");
    m.def("mip_level", &mip_level, "lod"_a, "levels"_a);

    nb::class_<ResidencyLookup>(m, "ResidencyLookup",
                                "The page table's answer: finest resident level covering a request.")
        .def("resident_level", &ResidencyLookup::resident_level, "request"_a)
        .def("response", [](const ResidencyLookup& r, std::uint64_t key) { return response_of(r, key); },
             "request"_a);

    nb::class_<VirtualTextureLookup, ResidencyLookup>(
        m, "VirtualTextureLookup", "Request processing's view of a VirtualTexture's page table.")
        .def(nb::init<const VirtualTexture&>(), "vt"_a, nb::keep_alive<1, 2>());

    nb::class_<ResidentSet, ResidencyLookup>(
        m, "ResidentSet", "Reference residency: a set of tiles plus every painting's coarsest tile.")
        .def(nb::init<std::vector<PaintingTiles>>(), "paintings"_a)
        .def("insert", [](ResidentSet& s, nb::handle keys) {
            if (nb::isinstance<nb::int_>(keys)) return s.insert(nb::cast<std::uint64_t>(keys));
            HeldBuffer b = as_buffer(keys, "keys");
            for (std::uint64_t k : b.view) s.insert(k);
        }, "keys"_a)
        .def("erase", &ResidentSet::erase, "key"_a)
        .def("__contains__", &ResidentSet::contains)
        .def("__len__", &ResidentSet::size);

    nb::class_<BasicProcessor>(m, "BasicProcessor", "Barrett: one thread, a hash set of pixels.")
        .def(nb::init<>())
        .def("process", &process_frame<BasicProcessor>, "buffers"_a, "lookup"_a, "frame"_a = 0);

    nb::class_<FlagArrayProcessor>(m, "FlagArrayProcessor",
                                   "Hollemeersch: one flag per tile, parallel mark and compaction.")
        .def(nb::init<std::vector<PaintingTiles>, unsigned>(), "paintings"_a, "threads"_a = 0)
        .def_prop_ro("flag_count", &FlagArrayProcessor::flag_count)
        .def("process", &process_frame<FlagArrayProcessor>, "buffers"_a, "lookup"_a, "frame"_a = 0);

    nb::class_<HashProcessor>(m, "HashProcessor",
                              "Seed 000: fixed-size result table, slot a (B F) mod m, finer level wins.")
        .def("__init__", [](HashProcessor* h, unsigned table_bits, const std::string& modulus,
                            unsigned threads) {
            require(modulus == "pow2" || modulus == "prime", "modulus must be 'pow2' or 'prime'");
            new (h) HashProcessor(table_bits, modulus == "pow2" ? HashModulus::Pow2 : HashModulus::Prime,
                                  threads);
        }, "table_bits"_a = 16, "modulus"_a = "pow2", "threads"_a = 0)
        .def_prop_ro("table_size", &HashProcessor::table_size)
        .def_static("frame_salt", &HashProcessor::frame_salt, "frame"_a)
        .def("slot", &HashProcessor::slot, "key"_a, "salt"_a)
        .def("process", &process_frame<HashProcessor>, "buffers"_a, "lookup"_a, "frame"_a);

    nb::class_<AsyncProcessor>(m, "AsyncProcessor",
                               "Unreal SVT: a worker thread deduplicates; results arrive frames later.")
        .def(nb::init<>())
        .def("submit", [](AsyncProcessor& p, nb::handle buffers, std::uint64_t frame) {
            auto held = as_buffers(buffers);
            auto views = views_of(held);
            nb::gil_scoped_release release;
            p.submit(views, frame);
        }, "buffers"_a, "frame"_a)
        .def("poll", [](AsyncProcessor& p, const ResidencyLookup& lookup, bool wait) {
            std::vector<AsyncProcessor::Result> results;
            {
                nb::gil_scoped_release release;
                results = wait ? p.drain(lookup) : p.poll(lookup);
            }
            nb::list out;
            for (auto& r : results) {
                nb::dict d = sets_dict(std::move(r.sets));
                d["frame"] = r.frame;
                d["seconds"] = r.seconds;
                out.append(d);
            }
            return out;
        }, "lookup"_a, "wait"_a = false,
             "Finished frames as dicts with 'frame' (submit frame), 'seconds' (submit to\n"
             "finish) and the three sets;\n"
             "wait=True blocks until every submitted frame is done.")
        .def_prop_ro("pending", &AsyncProcessor::pending);

    nb::class_<DirectLoading>(m, "DirectLoading",
                              "Seed 000: load missing requested tiles, at most per_frame a frame.")
        .def(nb::init<std::size_t>(), "per_frame"_a = 16)
        .def("set_commands", [](DirectLoading& d, nb::handle keys) {
            HeldBuffer b = as_buffer(keys, "commands");
            d.set_commands(b.view);
        }, "commands"_a)
        .def("issue", [](DirectLoading& d, const ResidencyLookup& lookup) {
            return to_numpy(d.issue(lookup));
        }, "lookup"_a)
        .def("loaded", [](DirectLoading& d, nb::handle keys) {
            HeldBuffer b = as_buffer(keys, "keys");
            d.loaded(b.view);
        }, "keys"_a)
        .def_prop_ro("backlog", &DirectLoading::backlog)
        .def_prop_ro("in_flight", &DirectLoading::in_flight);

    nb::class_<MipByMipLoading>(m, "MipByMipLoading",
                                "van Waveren: the coarsest missing ancestor of each miss first.")
        .def(nb::init<std::size_t>(), "per_frame"_a = 16)
        .def("issue", [](MipByMipLoading& d, nb::handle commands, const ResidencyLookup& lookup) {
            HeldBuffer b = as_buffer(commands, "commands");
            return to_numpy(d.issue(b.view, lookup));
        }, "commands"_a, "lookup"_a)
        .def("loaded", [](MipByMipLoading& d, nb::handle keys) {
            HeldBuffer b = as_buffer(keys, "keys");
            d.loaded(b.view);
        }, "keys"_a)
        .def_prop_ro("in_flight", &MipByMipLoading::in_flight);

    nb::class_<VisibilityLists>(m, "VisibilityLists",
                                "Seed 002: alive and remove lists against the previous frame.")
        .def(nb::init<std::vector<PaintingTiles>, unsigned>(), "paintings"_a, "threads"_a = 0)
        .def("process", [](VisibilityLists& v, nb::handle buffers) {
            auto held = as_buffers(buffers);
            auto views = views_of(held);
            VisibilityLists::Lists lists;
            {
                nb::gil_scoped_release release;
                lists = v.process(views);
            }
            nb::dict d;
            d["alive"] = to_numpy(std::move(lists.alive));
            d["remove"] = to_numpy(std::move(lists.remove));
            return d;
        }, "buffers"_a);
}

}  // namespace gigascroll::bindings
