// pack/: the reader (TilePack), the streaming builder (PackBuilder), pack geometry and tile keys.
#include <nanobind/ndarray.h>
#include <nanobind/stl/filesystem.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <filesystem>
#include <functional>

#include "bindings/bindings.h"
#include "bindings/arrays.h"
#include "common/error.h"
#include "common/limits.h"
#include "pack/ink_landscape.h"
#include "pack/builder.h"
#include "pack/colour.h"
#include "pack/geometry.h"
#include "pack/page_layout.h"
#include "pack/geometry.h"
#include "pack/tile_key.h"
#include "pack/manifest.h"
#include "pack/reader.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {

using Rows = nb::ndarray<const std::uint8_t, nb::ndim<3>, nb::c_contig, nb::device::cpu>;
using TileOut = nb::ndarray<std::uint8_t, nb::ndim<3>, nb::c_contig, nb::device::cpu>;

nb::dict geometry_dict(const PaintingGeometry& g) {
    nb::dict d;
    d["width"] = g.width();
    d["height"] = g.height();
    d["tile_size"] = g.tile_size();
    d["border"] = g.border();
    d["payload"] = g.payload();
    d["table_size"] = std::make_pair(g.page_table_width(), g.page_table_height());
    d["uv_scale"] = std::make_pair(g.uv_scale_u(), g.uv_scale_v());
    d["tile_count"] = g.total_tiles();
    nb::list levels;
    for (std::uint32_t l = 0; l < g.levels(); ++l) {
        const LevelGeometry& lv = g.level(l);
        nb::dict dl;
        dl["size"] = std::make_pair(lv.width, lv.height);
        dl["tiles"] = std::make_pair(lv.tiles_x, lv.tiles_y);
        dl["first_entry"] = lv.first_tile;
        levels.append(dl);
    }
    d["levels"] = levels;
    return d;
}

std::vector<std::pair<std::uint32_t, std::uint32_t>> level_pairs(const PaintingGeometry& g,
                                                                  bool tiles) {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> out;
    for (std::uint32_t l = 0; l < g.levels(); ++l) {
        const LevelGeometry& lv = g.level(l);
        out.emplace_back(tiles ? lv.tiles_x : lv.width, tiles ? lv.tiles_y : lv.height);
    }
    return out;
}

template <typename T>
nb::ndarray<nb::numpy, std::uint16_t, nb::ndim<3>> icc_apply(
    const IccTransform& t, nb::ndarray<const T, nb::ndim<3>, nb::c_contig, nb::device::cpu> band,
    unsigned threads) {
    require(band.shape(2) == t.channels(),
            "band must have shape (h, w, " + std::to_string(t.channels()) + ")");
    const std::size_t h = band.shape(0), w = band.shape(1);
    FreshArray<std::uint16_t, nb::ndim<3>> out({h, w, 3});
    {
        nb::gil_scoped_release release;
        t.apply(band.data(), h * w, out.data, threads);
    }
    return out.array;
}

void check_tile_out(const TilePack& pack, const TileOut& out) {
    const std::size_t T = pack.tile_size();
    require(out.shape(0) == T && out.shape(1) == T && out.shape(2) == 3,
            "out must have shape (" + std::to_string(T) + ", " + std::to_string(T) + ", 3)");
}

// The index of `painting` in `pack`: the README passes a painting object (pack.paintings[i],
// a reference into the pack's own list) where the core takes its index.
std::uint32_t painting_index(const TilePack& pack, const PaintingInfo& painting) {
    const std::vector<PaintingInfo>& all = pack.paintings();
    const std::less<const PaintingInfo*> before;  // a total order even on unrelated pointers
    if (!all.empty() && !before(&painting, all.data()) && before(&painting, all.data() + all.size()))
        return static_cast<std::uint32_t>(&painting - all.data());
    throw InvalidArgument("painting '" + painting.name + "' is not one of this pack's paintings "
                          "(pass pack.paintings[i] of this pack, or the index i)");
}

bool has_tile_at(const TilePack& p, std::uint32_t pi, std::uint32_t l, std::uint32_t tx,
                 std::uint32_t ty) {
    return p.has_tile(pi, l, tx, ty);
}

std::tuple<std::uint64_t, std::uint32_t, std::uint64_t> locate_at(
    const TilePack& p, std::uint32_t pi, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) {
    const TileLocation loc = p.locate(pi, l, tx, ty);
    return {loc.offset, loc.length, loc.checksum};
}

std::string tile_file_at(const TilePack& p, std::uint32_t pi, std::uint32_t l, std::uint32_t tx,
                         std::uint32_t ty) {
    return p.tile_files()[p.locate(pi, l, tx, ty).file];
}

nb::ndarray<nb::numpy, std::uint8_t, nb::ndim<3>> read_tile_at(
    const TilePack& p, std::uint32_t pi, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) {
    const std::size_t T = p.tile_size();
    FreshArray<std::uint8_t, nb::ndim<3>> tile({T, T, 3});
    {
        nb::gil_scoped_release release;
        p.read_tile(pi, l, tx, ty, tile.data);  // on throw, the array frees the buffer
    }
    return tile.array;
}

nb::ndarray<nb::numpy, std::uint8_t, nb::ndim<3>> read_slot_tile_at(
    const TilePack& p, std::uint32_t pi, std::uint32_t l, std::uint32_t tx, std::uint32_t ty) {
    const auto shape = texel_format_tile_shape(p.slot_format(), p.tile_size());
    FreshArray<std::uint8_t, nb::ndim<3>> tile({shape[0], shape[1], shape[2]});
    {
        nb::gil_scoped_release release;
        p.read_slot_tile(pi, l, tx, ty, tile.data);
    }
    return tile.array;
}

void read_tile_into_at(const TilePack& p, std::uint32_t pi, std::uint32_t l, std::uint32_t tx,
                       std::uint32_t ty, TileOut out) {
    check_tile_out(p, out);
    nb::gil_scoped_release release;
    p.read_tile(pi, l, tx, ty, out.data());
}

// Fn(pack, painting index, rest...) as Fn(pack, painting object, rest...): the second overload
// of each per-tile method.
template <auto Fn>
struct ByPainting;
template <typename R, typename... Rest, R (*Fn)(const TilePack&, std::uint32_t, Rest...)>
struct ByPainting<Fn> {
    static R call(const TilePack& p, const PaintingInfo& painting, Rest... rest) {
        return Fn(p, painting_index(p, painting), rest...);
    }
};

// Binds `name` twice: with the painting's index and with the painting object itself.
template <auto Fn, typename... Extra>
void def_per_tile(nb::class_<TilePack>& c, const char* name, const Extra&... extra) {
    c.def(name, Fn, "painting"_a, "level"_a, "tx"_a, "ty"_a, extra...);
    c.def(name, &ByPainting<Fn>::call, "painting"_a, "level"_a, "tx"_a, "ty"_a, extra...);
}

}  // namespace

void bind_pack(nb::module_& m) {
    m.attr("NO_REQUEST") = kNoRequest;

    nb::class_<PaintingGeometry>(m, "PaintingGeometry",
                              "Tile pyramid geometry of one painting (levels, tiles per level).")
        .def(nb::init<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>(), "width"_a,
             "height"_a, "tile_size"_a = 128, "border"_a = 4)
        .def_prop_ro("width", &PaintingGeometry::width)
        .def_prop_ro("height", &PaintingGeometry::height)
        .def_prop_ro("tile_size", &PaintingGeometry::tile_size)
        .def_prop_ro("border", &PaintingGeometry::border)
        .def_prop_ro("payload", &PaintingGeometry::payload)
        .def_prop_ro("levels", &PaintingGeometry::levels)
        .def_prop_ro("total_tiles", &PaintingGeometry::total_tiles)
        .def_prop_ro("page_table_width", &PaintingGeometry::page_table_width)
        .def_prop_ro("page_table_height", &PaintingGeometry::page_table_height)
        .def("level_width", &PaintingGeometry::level_width)
        .def("level_height", &PaintingGeometry::level_height)
        .def("tiles_x", &PaintingGeometry::tiles_x)
        .def("tiles_y", &PaintingGeometry::tiles_y)
        .def("tile_count", &PaintingGeometry::tile_count)
        .def("__repr__", [](const PaintingGeometry& p) {
            return "PaintingGeometry(" + std::to_string(p.width()) + ", " + std::to_string(p.height()) +
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
            const TileKey r = unpack_request(b.view[i]);
            p[i] = r.painting, l[i] = r.level, x[i] = r.tx, y[i] = r.ty;
        }
        return nb::make_tuple(to_numpy(std::move(p)), to_numpy(std::move(l)),
                              to_numpy(std::move(x)), to_numpy(std::move(y)));
    }, "keys"_a, "Split request keys into (painting, level, x, y) uint32 arrays (flattened).");

    nb::class_<PaintingInfo>(m, "PackPainting", "One painting of a tile pack (read-only).")
        .def_ro("name", &PaintingInfo::name)
        .def_ro("source", &PaintingInfo::source)
        .def_ro("conversion", &PaintingInfo::conversion)
        .def_prop_ro("colour", [](const PaintingInfo& p) -> nb::object {
            if (p.colour.empty()) return nb::none();
            return nb::module_::import_("json").attr("loads")(p.colour); },
            "colour management at ingest (dict: source profile, intent, transform) or None")
        .def_prop_ro("width", [](const PaintingInfo& p) { return p.geometry.width(); })
        .def_prop_ro("height", [](const PaintingInfo& p) { return p.geometry.height(); })
        .def_prop_ro("levels", [](const PaintingInfo& p) { return p.geometry.levels(); },
                     "number of mip levels")
        .def_prop_ro("level_sizes", [](const PaintingInfo& p) { return level_pairs(p.geometry, false); },
                     "(width, height) in texels of each level")
        .def_prop_ro("level_tiles", [](const PaintingInfo& p) { return level_pairs(p.geometry, true); },
                     "(tiles_x, tiles_y) real tiles of each level")
        .def_prop_ro("table_size", [](const PaintingInfo& p) {
            return std::make_pair(p.geometry.page_table_width(), p.geometry.page_table_height()); },
            "(Mp, Np): the painting's power-of-two level-0 page table")
        .def_prop_ro("table_offset", [](const PaintingInfo& p) {
            return std::make_pair(p.geometry.table_x(), p.geometry.table_y()); },
            "(x, y) offset of its page table in the merged table")
        .def_prop_ro("uv_scale", [](const PaintingInfo& p) {
            return std::make_pair(p.geometry.uv_scale_u(), p.geometry.uv_scale_v()); },
            "(W / (Mp P), H / (Np P)): VT-mobile-VR eqs (3, 4)")
        .def_prop_ro("tile_count", [](const PaintingInfo& p) { return p.geometry.total_tiles(); })
        .def_prop_ro("instance_of", [](const PaintingInfo& p) -> nb::object {
            if (p.instance_of < 0) return nb::none();
            return nb::int_(p.instance_of); },
            "the index of the painting whose tiles this one shares, or None (it stores its own)")
        .def("__repr__", [](const PaintingInfo& p) {
            const PaintingGeometry& g = p.geometry;
            return "PackPainting('" + p.name + "', " + std::to_string(g.width()) + " x " +
                   std::to_string(g.height()) + ", " + std::to_string(g.levels()) + " levels)";
        });

    nb::class_<TilePack> pack(m, "TilePack",
                         "A tile pack opened for reading. Thread-safe; reads release the GIL.");
    pack.def("__init__", [](TilePack* self, const std::filesystem::path& path) {
            new (self) TilePack(path.string());
            for (const std::string& w : self->warnings())
                if (PyErr_WarnEx(PyExc_UserWarning, w.c_str(), 1) != 0) throw nb::python_error();
            }, "path"_a)
        .def_prop_ro("version", &TilePack::version, "format version of the pack (1 or 2)")
        .def_prop_ro("tile_files", &TilePack::tile_files, "the tile files, in TileEntry::file order")
        .def_prop_ro("path", &TilePack::directory)
        .def_prop_ro("paintings", &TilePack::paintings, nb::rv_policy::reference_internal)
        .def_prop_ro("tile_size", &TilePack::tile_size)
        .def_prop_ro("border", &TilePack::border)
        .def_prop_ro("payload", &TilePack::payload)
        .def_prop_ro("codec", [](const TilePack& p) { return std::string(codec_name(p.codec())); })
        .def_prop_ro("table_size", [](const TilePack& p) {
            return std::make_pair(p.table_width(), p.table_height()); },
            "(Mc, Nc): size of the merged page table")
        .def_prop_ro("tile_count", &TilePack::tile_count)
        .def("manifest_json", &TilePack::manifest_json,
             "The manifest as the core's reader parsed it (JSON text).")
        .def_prop_ro("slot_format", [](const TilePack& p) { return std::string(texel_format_name(p.slot_format())); },
                     "'bc1' when the cache keeps this pack's tiles block-compressed, else 'rgb8'.")
        .def_prop_ro("slot_bytes", &TilePack::slot_bytes, "Bytes of one tile in the cache.");
    // Per-tile methods take the painting as its index or as the object in pack.paintings.
    def_per_tile<&has_tile_at>(pack, "has_tile", "False for padding tiles.");
    def_per_tile<&locate_at>(pack, "locate", "(offset, length, checksum) in its tile file");
    def_per_tile<&tile_file_at>(pack, "tile_file", "name of the tile file holding the tile");
    def_per_tile<&read_tile_at>(pack, "read_tile",
        "The tile as a (tile_size, tile_size, 3) uint8 array, checksum verified.");
    def_per_tile<&read_slot_tile_at>(pack, "read_slot_tile",
        "The tile as the cache keeps it, checksum verified: (tile_size / 4, tile_size / 4, 8) "
        "BC1 blocks (row-major) for a bc1 pack, else what read_tile gives.");
    def_per_tile<&read_tile_into_at>(pack, "read_tile_into", "out"_a.noconvert(),
        "Reads the tile into a C-contiguous (tile_size, tile_size, 3) uint8 array.");

    nb::class_<PackBuilder>(m, "PackBuilder",
                            "Low-level streaming pack writer; use gigascroll.build_pack instead.")
        .def("__init__", [](PackBuilder* self, const std::filesystem::path& dir,
                            std::uint32_t tile_size, std::uint32_t border, const std::string& codec,
                            int zstd_level, unsigned threads, const std::string& bc1_fit,
                            std::uint32_t first_painting) {
            PackOptions o;
            o.bc1_fit = parse_bc1_fit(bc1_fit);
            o.tile_size = tile_size;
            o.border = border;
            o.codec = parse_codec(codec);
            o.zstd_level = zstd_level;
            o.threads = threads;
            new (self) PackBuilder(dir.string(), o, first_painting); },
            "directory"_a, "tile_size"_a = 128, "border"_a = 4, "codec"_a = "raw",
            "zstd_level"_a = 3, "threads"_a = 0, "bc1_fit"_a = "range", "first_painting"_a = 0)
        .def("begin_painting", [](PackBuilder& b, const std::string& name, std::uint32_t width,
                                  std::uint32_t height, const std::string& source,
                                  const std::string& conversion, std::uint32_t tx, std::uint32_t ty,
                                  const std::string& colour) {
            b.begin_painting(PaintingSpec{name, source, conversion, width, height, tx, ty, colour}); },
            "name"_a, "width"_a, "height"_a, "source"_a = "", "conversion"_a = "",
            "table_x"_a = 0, "table_y"_a = 0, "colour"_a = "")
        .def("add_rows", [](PackBuilder& b, Rows rows) {
            require(rows.shape(2) == 3, "rows must have shape (n, width, 3)");
            nb::gil_scoped_release release;
            b.add_rows(rows.data(), static_cast<std::uint32_t>(rows.shape(0)),
                       static_cast<std::uint32_t>(rows.shape(1))); },
            "rows"_a, "uint8 array (n, width, 3), the next rows of the current painting")
        .def("end_painting", &PackBuilder::end_painting)
        .def("add_instance", [](PackBuilder& b, const std::string& name, std::uint32_t source,
                                std::uint32_t tx, std::uint32_t ty) {
            PaintingSpec s{name, "", "", 0, 0, tx, ty, ""};
            s.instance_of = source;
            b.add_instance(s); },
            "name"_a, "source"_a, "table_x"_a = 0, "table_y"_a = 0,
            "Adds a painting sharing stored painting `source`'s tiles, after every stored one.")
        .def("finish", &PackBuilder::finish, "table_width"_a, "table_height"_a,
             "page_table_json"_a = "{}")
        .def("finish_shard", &PackBuilder::finish_shard)
        .def_static("assemble", [](const std::filesystem::path& dir, std::uint32_t tile_size,
                                   std::uint32_t border, const std::string& codec,
                                   const std::vector<std::tuple<std::string, std::uint32_t, std::uint32_t,
                                                                std::string, std::string, std::uint32_t,
                                                                std::uint32_t, std::string>>& paintings,
                                   std::uint32_t table_width, std::uint32_t table_height,
                                   const std::string& page_table_json,
                                   const std::vector<std::tuple<std::string, std::uint32_t,
                                                                std::uint32_t, std::uint32_t>>& instances) {
            PackOptions o;
            o.tile_size = tile_size;
            o.border = border;
            o.codec = parse_codec(codec);
            std::vector<PaintingSpec> specs;
            for (const auto& [name, w, h, source, conversion, x, y, colour] : paintings)
                specs.push_back(PaintingSpec{name, source, conversion, w, h, x, y, colour});
            for (const auto& [name, source, x, y] : instances) {
                specs.push_back(PaintingSpec{name, "", "", 0, 0, x, y, ""});
                specs.back().instance_of = source;
            }
            nb::gil_scoped_release release;
            PackBuilder::assemble(dir.string(), o, specs, table_width, table_height, page_table_json); },
            "directory"_a, "tile_size"_a, "border"_a, "codec"_a, "paintings"_a, "table_width"_a,
            "table_height"_a, "page_table_json"_a = "{}",
            "instances"_a = std::vector<std::tuple<std::string, std::uint32_t, std::uint32_t, std::uint32_t>>{},
            "Merges shards (paintings: (name, width, height, source, conversion, table_x, table_y, "
            "colour) each) into a pack: writes index.bin and manifest.json. instances: (name, "
            "source painting, table_x, table_y) each, after the stored paintings.")
        .def_prop_ro("rows_done", &PackBuilder::rows_done)
        .def_prop_ro("tiles_written", &PackBuilder::tiles_written)
        .def_prop_ro("bytes_written", &PackBuilder::bytes_written);

    nb::class_<IccTransform>(m, "IccTransform",
                             "LittleCMS transform of an RGB, grey or CMYK ICC profile to sRGB, 16 bits.")
        .def("__init__", [](IccTransform* self, nb::bytes profile, const std::string& intent,
                            bool bpc) {
            const auto* p = static_cast<const std::uint8_t*>(profile.data());
            new (self) IccTransform(std::vector<std::uint8_t>(p, p + profile.size()),
                                    parse_intent(intent), bpc); },
            "profile"_a, "intent"_a = "relative", "black_point_compensation"_a = true)
        .def_prop_ro("channels", &IccTransform::channels)
        .def("apply", &icc_apply<std::uint16_t>, "band"_a.noconvert(), "threads"_a = 0,
             "(h, w, channels) uint16 in the profile's space -> (h, w, 3) uint16 sRGB.")
        .def("apply", &icc_apply<std::uint8_t>, "band"_a.noconvert(), "threads"_a = 0,
             "(h, w, channels) uint8 in the profile's space -> (h, w, 3) uint16 sRGB.");
    m.def("lcms_version", &lcms_version, "LittleCMS version the core links.");

    m.def("render_ink_landscape", [](std::uint32_t width, std::uint32_t height, std::uint32_t y0,
                                     std::uint32_t rows, std::uint64_t seed, unsigned threads) {
        require(std::uint64_t(y0) + rows <= height && rows > 0 && width > 0,
                "rows [y0, y0 + rows) must be a non-empty range inside the painting");
        require_threads(threads, "render_ink_landscape");
        require_memory(double(rows) * width, 3, double(std::size_t(4) << 30),
                       "render_ink_landscape: " + std::to_string(rows) + " rows of " + std::to_string(width) + " texels");
        FreshArray<std::uint8_t, nb::ndim<3>> out({rows, width, 3});
        {
            nb::gil_scoped_release release;
            render_ink_landscape(width, height, y0, rows, seed, out.data, threads);
        }
        return out.array; },
        "width"_a, "height"_a, "y0"_a, "rows"_a, "seed"_a = 0, "threads"_a = 0,
        "Rows [y0, y0 + rows) of the built-in ink-landscape painting as (rows, width, 3) uint8.");

    m.def("layout_page_tables", [](const std::vector<std::pair<std::uint32_t, std::uint32_t>>& sizes,
                                   const std::string& method, std::uint64_t seed) {
        std::vector<TableSize> tables;
        for (auto [w, h] : sizes) tables.push_back({w, h});
        PlannedLayout plan;
        {
            nb::gil_scoped_release release;
            plan = plan_layout(tables, method, seed);
        }
        const PageLayout &chosen = plan.chosen, &shelf = plan.shelf, &brkga = plan.brkga;
        nb::dict info;
        info["packer"] = method;
        info["fill_ratio"] = chosen.fill_ratio;
        info["shelf_fill_ratio"] = shelf.fill_ratio;
        info["shelf_size"] = std::make_pair(shelf.width, shelf.height);
        if (brkga.width > 0) {  // the GA ran (not for the shelf layout)
            info["brkga_fill_ratio"] = brkga.fill_ratio;
            info["brkga_size"] = std::make_pair(brkga.width, brkga.height);
        }
        info["seed"] = seed;
        return std::make_tuple(chosen.width, chosen.height, chosen.offsets, info); },
        "sizes"_a, "method"_a = "brkga", "seed"_a = 0,
        "Packs power-of-two page tables (Mp, Np) into one merged table; returns "
        "(width, height, offsets, info) with the packers' fill ratios in info (the BRKGA's only "
        "when it ran: method 'brkga').");

    m.def("painting_geometry", [](std::uint32_t w, std::uint32_t h, std::uint32_t tile_size,
                                  std::uint32_t border) {
        return geometry_dict(PaintingGeometry(w, h, tile_size, border)); },
        "width"_a, "height"_a, "tile_size"_a = 128, "border"_a = 4,
        "Mip levels, tile grids, page-table size and UV scale of a painting.");

    m.def("check_manifest", [](const std::string& text) { (void)parse_manifest(text); },
          "text"_a, "Validates manifest.json text as the core's reader does (ValueError if not).");
    m.attr("PACK_VERSION") = kPackVersion;
    m.attr("MAX_PACK_PAINTINGS") = kMaxPackPaintings;
}

}  // namespace gigascroll::bindings
