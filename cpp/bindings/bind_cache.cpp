// cache/: the physical tile cache with its page table, its lookup for request processing,
// and the frame's drain from the loader.
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

#include "cache/drain.h"
#include "cache/lookup.h"
#include "cache/virtual_texture.h"
#include "pack/reader.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {
using TileIn = nb::ndarray<const std::uint8_t, nb::ndim<3>, nb::c_contig, nb::device::cpu>;
nb::dict stats_dict(const CacheStats& s) {
    nb::dict d;
    d["resident"] = s.resident;
    d["pinned"] = s.pinned;
    d["slots"] = s.slots;
    d["insertions"] = s.insertions;
    d["evictions"] = s.evictions;
    d["hits"] = s.hits;
    d["misses"] = s.misses;
    return d;
}

}  // namespace

void bind_cache(nb::module_& m) {
    nb::class_<VirtualTexture>(m, "VirtualTexture",
        "Physical tile cache (LRU, coarse tiles pinned) with its mip-mapped page table and "
        "software VT sampling.")
        .def("__init__", [](VirtualTexture* self, const TilePack& pack, std::pair<std::uint32_t, std::uint32_t> slots) {
            nb::gil_scoped_release release;
            new (self) VirtualTexture(pack, slots.first, slots.second); },
            "pack"_a, "slots"_a = std::make_pair(30u, 30u))
        .def_prop_ro("slots", [](const VirtualTexture& vt) { return std::make_pair(vt.slots_x(), vt.slots_y()); })
        .def_prop_ro("tile_size", [](const VirtualTexture& vt) { return vt.layout().tile_size; })
        .def_prop_ro("format", [](const VirtualTexture& vt) { return std::string(texel_format_name(vt.format())); },
                     "'rgb8' or 'bc1': how the slots hold their tiles.")
        .def_prop_ro("slot_bytes", &VirtualTexture::slot_bytes)
        .def("insert", [](VirtualTexture& vt, const KeyTuple& key, const TileIn& data) {
            const auto shape = texel_format_tile_shape(vt.format(), vt.layout().tile_size);
            require(data.shape(0) == shape[0] && data.shape(1) == shape[1] && data.shape(2) == shape[2],
                    "tile data must be a (" + std::to_string(shape[0]) + ", " + std::to_string(shape[1]) +
                        ", " + std::to_string(shape[2]) + ") uint8 array (" +
                        texel_format_name(vt.format()) + " slots)");
            const auto ev = vt.insert(to_key(key), data.data());
            return ev ? std::optional<KeyTuple>(to_tuple(*ev)) : std::nullopt; },
            "key"_a, "data"_a, "Copies a tile into the cache; returns the evicted tile's key, if any.")
        .def("drain", [](VirtualTexture& vt, TileLoader& loader, std::size_t max) {
            DrainResult r;
            {
                nb::gil_scoped_release release;
                r = drain(loader, vt, max);
            }
            std::vector<std::pair<KeyTuple, std::string>> failed;
            for (auto& [k, e] : r.failed) failed.emplace_back(to_tuple(k), std::move(e));
            return std::make_pair(to_numpy(std::move(r.arrived)), failed); },
            "loader"_a, "max_tiles"_a = std::size_t(-1),
            "The frame's drain: polls the loader and inserts its finished tiles in C++; returns "
            "(arrived, failed): the request keys (uint64) of every tile that came back, and "
            "[(key, error), ...] of the loads that failed.")
        .def("_request_keys", [](VirtualTexture& vt, const RequestKeys& keys) {
            std::vector<std::uint64_t> out;
            for (const auto& k : vt.request(to_tile_keys(keys))) out.push_back(pack_request(k));
            return to_numpy(std::move(out)); }, "keys"_a)
        .def("request", [](VirtualTexture& vt, const Keys& keys) {
            const auto missing = vt.request(to_keys(keys));
            std::vector<KeyTuple> out;
            for (const auto& k : missing) out.push_back(to_tuple(k));
            return out; }, "keys"_a)
        .def("is_resident", [](const VirtualTexture& vt, const KeyTuple& k) { return vt.is_resident(to_key(k)); }, "key"_a)
        .def("is_pinned", [](const VirtualTexture& vt, const KeyTuple& k) { return vt.is_pinned(to_key(k)); }, "key"_a)
        .def("lookup", [](const VirtualTexture& vt, const KeyTuple& k) {
            const PageEntry e = vt.lookup(to_key(k));
            return std::make_pair(e.level(), e.slot()); }, "key"_a,
            "(level, slot) of the finest resident tile covering the key.")
        .def("resident_tiles", [](const VirtualTexture& vt) {
            std::vector<KeyTuple> out;
            for (const auto& k : vt.resident_tiles()) out.push_back(to_tuple(k));
            return out; })
        .def("stats", [](const VirtualTexture& vt) { return stats_dict(vt.stats()); })
        .def("page_table_matches_rebuild", [](const VirtualTexture& vt) {
            nb::gil_scoped_release release;
            return vt.page_table_matches_rebuild(); },
            "Whether the incrementally updated page table equals a full rebuild (tests).")
        .def_prop_ro("physical", [](const VirtualTexture& vt) {
            const auto shape = texel_format_tile_shape(vt.format(), vt.layout().tile_size);
            return nb::ndarray<nb::numpy, const std::uint8_t, nb::ndim<4>>(
                vt.physical(), {std::size_t(vt.slots_y()) * vt.slots_x(), shape[0], shape[1], shape[2]},
                nb::handle()); },
            nb::rv_policy::reference_internal,
            "The physical texture, tile-major (read-only view): [slot, y, x, rgb], or "
            "[slot, block_y, block_x, 8] for bc1 slots.");

    nb::class_<VirtualTextureLookup, ResidencyLookup>(
        m, "VirtualTextureLookup", "Request processing's view of a VirtualTexture's page table.")
        .def(nb::init<const VirtualTexture&>(), "vt"_a, nb::keep_alive<1, 2>());

}

}  // namespace gigascroll::bindings
