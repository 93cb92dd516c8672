// views/: cameras, the exhibition scene, the feedback pass and request processing.
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

#include <type_traits>

#include "views/camera.h"
#include "views/exhibition.h"
#include "views/feedback.h"
#include "views/request_hash.h"
#include "views/request_processing.h"
#include "views/residency.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {

Vec3d vec3(const std::array<double, 3>& a) { return {a[0], a[1], a[2]}; }
std::array<double, 3> arr3(Vec3d v) { return {v.x, v.y, v.z}; }

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

}  // namespace

void bind_views(nb::module_& m) {
    nb::class_<Camera>(m, "Camera",
        "The pinhole camera of every view: Camera(position, look_at, up, fov=45, resolution=(w, h))\n"
        "with a vertical field of view in degrees, or Camera(position, forward, up, tan_half_x,\n"
        "tan_half_y, width, height). Pixel (0, 0) is the top-left corner.")
        .def("__init__", [](Camera* c, std::array<double, 3> position, std::array<double, 3> forward,
                            std::array<double, 3> up, double tan_half_x, double tan_half_y,
                            std::int64_t width, std::int64_t height) {
            require(width > 0 && height > 0 && width < (1 << 20) && height < (1 << 20),
                    "camera resolution must be positive");
            new (c) Camera(vec3(position), vec3(forward), vec3(up), tan_half_x, tan_half_y,
                           std::uint32_t(width), std::uint32_t(height));
        }, "position"_a, "forward"_a, "up"_a, "tan_half_x"_a, "tan_half_y"_a, "width"_a, "height"_a)
        .def("__init__", [](Camera* c, std::array<double, 3> position, std::array<double, 3> look_at,
                            std::array<double, 3> up, double fov, std::array<std::int64_t, 2> res) {
            require(res[0] > 0 && res[1] > 0 && res[0] <= 65536 && res[1] <= 65536,
                    "Camera: resolution must be positive (at most 65536 per side)");
            new (c) Camera(Camera::look_at(vec3(position), vec3(look_at), vec3(up), fov,
                                           std::uint32_t(res[0]), std::uint32_t(res[1])));
        }, "position"_a, "look_at"_a, "up"_a, "fov"_a = 45.0,
           "resolution"_a = std::array<std::int64_t, 2>{256, 256})
        .def_prop_ro("position", [](const Camera& c) { return arr3(c.position); })
        .def_prop_ro("forward", [](const Camera& c) { return arr3(c.forward); })
        .def_prop_ro("up", [](const Camera& c) { return arr3(c.up); })
        .def_prop_ro("right", [](const Camera& c) { return arr3(c.right); })
        .def_ro("tan_half_x", &Camera::tan_half_x)
        .def_ro("tan_half_y", &Camera::tan_half_y)
        .def_ro("width", &Camera::width)
        .def_ro("height", &Camera::height)
        .def_prop_ro("fov", &Camera::fov_y_degrees, "vertical field of view in degrees")
        .def_prop_ro("resolution", [](const Camera& c) {
            return std::array<std::uint32_t, 2>{c.width, c.height}; })
        .def("project", [](const Camera& c, std::array<float, 3> p) -> nb::object {
            int x, y;
            if (!c.project(Vec3f(p[0], p[1], p[2]), x, y)) return nb::none();
            return nb::make_tuple(x, y);
        }, "point"_a, "Pixel (x, y) that sees point (VR-photon-mapping eqs. 3-5), or None off the film.")
        .def("direction", [](const Camera& c, double px, double py) {
            return arr3(normalize(c.direction(px, py)));
        }, "px"_a, "py"_a, "Unit direction through film position (px, py) in pixels.");

    nb::class_<StereoCamera>(m, "StereoCamera",
                             "Two parallel eyes ipd apart along the camera's right vector.")
        .def(nb::init<const Camera&, double>(), "camera"_a, "ipd"_a = 0.064)
        .def_ro("left", &StereoCamera::left)
        .def_ro("right", &StereoCamera::right)
        .def_ro("ipd", &StereoCamera::ipd);

    nb::class_<ExhibitionScene>(m, "ExhibitionScene",
                                "The exhibition room as an Embree scene: paintings, boxes, tables.")
        .def(nb::init<>())
        .def("add_painting", [](ExhibitionScene& s, std::int64_t painting, const PaintingGeometry& tiles,
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

    m.def("render_view", [](const ExhibitionScene& scene, const Camera& camera, std::int64_t width,
                            std::int64_t height, double lod_bias, unsigned threads,
                            std::int64_t display_step, bool display) {
        const FeedbackOptions o = checked_feedback_options(width, height, lod_bias, threads, display_step);
        const FeedbackShape s = feedback_shape(camera, o);
        FreshArray<std::uint64_t> keys({s.height, s.width});
        nb::dict d;
        d["keys"] = keys.array;
        d["display_step"] = display_step;
        if (!display) {
            {
                nb::gil_scoped_release release;
                render_view(scene, camera, o, keys.data);
            }
            d["lod"] = nb::none();
            d["uv"] = nb::none();
            return d;
        }
        FreshArray<float> lod({s.display_height, s.display_width});
        FreshArray<double> uv({s.display_height, s.display_width, 2});
        {
            nb::gil_scoped_release release;
            render_view(scene, camera, o, keys.data, lod.data, uv.data);
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

    nb::class_<ResidentSet, ResidencyLookup>(
        m, "ResidentSet", "Reference residency: a set of tiles plus every painting's coarsest tile.")
        .def(nb::init<std::vector<PaintingGeometry>>(), "paintings"_a)
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
        .def(nb::init<std::vector<PaintingGeometry>, unsigned>(), "paintings"_a, "threads"_a = 0)
        .def_prop_ro("flag_count", &FlagArrayProcessor::flag_count)
        .def("process", &process_frame<FlagArrayProcessor>, "buffers"_a, "lookup"_a, "frame"_a = 0);

    nb::class_<HashProcessor>(m, "HashProcessor",
                              "VT-mobile-VR: fixed-size result table, slot a (B F) mod m, finer level wins.")
        .def(nb::init<unsigned, unsigned>(), "table_bits"_a = 16, "threads"_a = 0)
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

    nb::class_<VisibilityLists>(m, "VisibilityLists",
                                "Vulkan-SVT: alive and remove lists against the previous frame.")
        .def(nb::init<std::vector<PaintingGeometry>, unsigned>(), "paintings"_a, "threads"_a = 0)
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
