// Runtime: tile loader, physical cache + page table (VirtualTexture), VT sampling and the plain
// mip texture. The Python layer (gigascroll/runtime.py) normalises keys and arrays; these
// bindings check dtype, shape and contiguity again and release the GIL for long calls.
#include <nanobind/ndarray.h>
#include <nanobind/stl/optional.h>
#include <nanobind/stl/pair.h>
#include <nanobind/stl/string.h>
#include <nanobind/stl/tuple.h>
#include <nanobind/stl/vector.h>

#include <cstring>
#include <string>

#include "bindings/bindings.h"
#include "bindings/numpy_arrays.h"
#include "common/error.h"
#include "vt/mip_texture.h"
#include "vt/tile_loader.h"
#include "vt/tile_pack.h"
#include "vt/virtual_texture.h"
#include "vt/drain.h"
#include "vt/vt_lookup.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {

using Keys = nb::ndarray<const std::int64_t, nb::ndim<2>, nb::device::cpu>;
using Coords = nb::ndarray<const double, nb::ndim<1>, nb::device::cpu>;
using Lods = nb::ndarray<const float, nb::ndim<1>, nb::device::cpu>;
using Values = nb::ndarray<float, nb::ndim<2>, nb::device::cpu>;
using Levels = nb::ndarray<std::int8_t, nb::ndim<1>, nb::device::cpu>;
using TileIn = nb::ndarray<const std::uint8_t, nb::ndim<3>, nb::device::cpu>;
using Tile = nb::ndarray<nb::numpy, std::uint8_t, nb::ndim<3>>;
using KeyTuple = std::tuple<std::uint32_t, std::uint32_t, std::uint32_t, std::uint32_t>;

TileKey to_key(const KeyTuple& k) {
    return {std::get<0>(k), std::get<1>(k), std::get<2>(k), std::get<3>(k)};
}
KeyTuple to_tuple(const TileKey& k) { return {k.painting, k.level, k.tx, k.ty}; }

std::vector<TileKey> to_keys(const Keys& a) {
    require(a.shape(1) == 4, "keys must have shape (n, 4): painting, level, tx, ty");
    std::vector<TileKey> keys(a.shape(0));
    if (keys.empty()) return keys;  // numpy gives empty arrays arbitrary strides
    require(a.stride(1) == 1 && (keys.size() == 1 || a.stride(0) == 4), "keys must be C-contiguous");
    const std::int64_t* d = a.data();
    for (std::size_t i = 0; i < keys.size(); ++i) {
        for (int c = 0; c < 4; ++c)
            require(d[4 * i + c] >= 0 && d[4 * i + c] < (1 << 20), "key values must be in [0, 2^20)");
        keys[i] = {std::uint32_t(d[4 * i]), std::uint32_t(d[4 * i + 1]), std::uint32_t(d[4 * i + 2]),
                   std::uint32_t(d[4 * i + 3])};
    }
    return keys;
}

using RequestKeys = nb::ndarray<const std::uint64_t, nb::ndim<1>, nb::c_contig, nb::device::cpu>;

// Request keys (views' pack_request layout) as tile keys; the loader and the cache check
// the ranges.
std::vector<TileKey> to_tile_keys(const RequestKeys& a) {
    std::vector<TileKey> keys(a.shape(0));
    for (std::size_t i = 0; i < keys.size(); ++i) keys[i] = tile_key_of(a.data()[i]);
    return keys;
}

Tile new_tile(std::size_t T, const std::uint8_t* src) {
    FreshArray<std::uint8_t, nb::ndim<3>> tile({T, T, 3});
    std::memcpy(tile.data, src, T * T * 3);
    return tile.array;
}

LoaderMode parse_mode(const std::string& m) {
    if (m == "lockfree") return LoaderMode::LockFree;
    if (m == "locked") return LoaderMode::Locked;
    throw InvalidArgument("mode must be 'lockfree' or 'locked', got '" + m + "'");
}

Filter parse_filter(const std::string& f) {
    if (f == "bilinear") return Filter::Bilinear;
    if (f == "trilinear") return Filter::Trilinear;
    throw InvalidArgument("filter must be 'bilinear' or 'trilinear', got '" + f + "'");
}

// Fills a SampleRequest from the arrays, checking sizes and contiguity.
SampleRequest sample_request(std::uint32_t painting, const Coords& u, const Coords& v,
                             const std::optional<Lods>& lod, float lod_scalar,
                             const std::string& filter, Values& out, Levels& levels,
                             unsigned threads) {
    const std::size_t n = u.shape(0);
    require(v.shape(0) == n, "u and v must have the same length");
    require(u.stride(0) == 1 && v.stride(0) == 1, "u and v must be contiguous");
    require(out.shape(0) == n && out.shape(1) == 3 && out.stride(1) == 1 && out.stride(0) == 3,
            "out must be a contiguous (n, 3) float32 array");
    require(levels.shape(0) == n && levels.stride(0) == 1, "levels must be a contiguous (n,) int8 array");
    SampleRequest r;
    r.painting = painting;
    r.u = u.data();
    r.v = v.data();
    if (lod) {
        require(lod->shape(0) == n && lod->stride(0) == 1, "lod must be a contiguous array of length n");
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

void bind_runtime(nb::module_& m) {
    nb::class_<TileLoader>(m, "TileLoader",
        "Asynchronous tile loading: 'lockfree' (SPSC command queues, MPSC result queue, the seed's "
        "design) or 'locked' (mutex job queue and result list, the Unreal-style baseline).")
        .def("__init__", [](TileLoader* self, const TilePack& pack, const std::string& mode,
                            unsigned threads, std::size_t queue_capacity, std::size_t pool_tiles) {
            LoaderOptions o;
            o.queue_capacity = queue_capacity;
            o.pool_tiles = pool_tiles;
            new (self) TileLoader(pack, parse_mode(mode), threads, o); },
            "pack"_a, "mode"_a = "lockfree", "threads"_a = 1, "queue_capacity"_a = 4096,
            "pool_tiles"_a = 64, nb::keep_alive<1, 2>())
        .def("_submit", [](TileLoader& l, const Keys& keys) {
            const auto k = to_keys(keys);
            l.submit(k.data(), k.size()); }, "keys"_a)
        .def("_submit_requests", [](TileLoader& l, const RequestKeys& keys) {
            const auto k = to_tile_keys(keys);
            l.submit(k.data(), k.size()); }, "keys"_a)
        .def("_poll", [](TileLoader& l, std::size_t max) {
            std::vector<LoadedTile> results;
            {
                nb::gil_scoped_release release;
                l.poll(results, max);
            }
            nb::list out;
            for (auto& r : results) {
                if (r.buffer >= 0) {
                    out.append(nb::make_tuple(to_tuple(r.key), new_tile(l.tile_size(), l.data(r.buffer))));
                    l.release(r.buffer);
                } else {
                    out.append(nb::make_tuple(to_tuple(r.key), r.error));
                }
            }
            return out; }, "max_tiles"_a)
        .def("discard", [](TileLoader& l, std::size_t max) {
            std::vector<LoadedTile> results;
            nb::gil_scoped_release release;
            l.poll(results, max);
            std::size_t ok = 0;
            for (auto& r : results)
                if (r.buffer >= 0) {
                    l.release(r.buffer);
                    ++ok;
                }
            return std::make_pair(ok, results.size() - ok); },
            "max_tiles"_a = std::size_t(-1),
            "Polls up to max_tiles finished tiles and drops their data (benchmarks); returns "
            "(loaded, failed).")
        .def("close", [](TileLoader& l) {
            nb::gil_scoped_release release;
            l.close(); }, "Stops the threads; queued commands are dropped, finished tiles stay pollable.")
        .def_prop_ro("closed", &TileLoader::closed)
        .def_prop_ro("mode", [](const TileLoader& l) {
            return std::string(l.mode() == LoaderMode::LockFree ? "lockfree" : "locked"); })
        .def_prop_ro("threads", &TileLoader::threads)
        .def("stats", [](const TileLoader& l) {
            const LoaderStats s = l.stats();
            nb::dict d;
            d["submitted"] = s.submitted;
            d["loaded"] = s.loaded;
            d["failed"] = s.failed;
            d["cancelled"] = s.cancelled;
            d["backlog"] = s.backlog;
            return d; });

    nb::class_<VirtualTexture>(m, "VirtualTexture",
        "Physical tile cache (LRU, coarse tiles pinned) with its mip-mapped page table and "
        "software VT sampling.")
        .def("__init__", [](VirtualTexture* self, const TilePack& pack, std::pair<std::uint32_t, std::uint32_t> slots) {
            const VtLayout layout = VtLayout::from_pack(pack);
            nb::gil_scoped_release release;
            new (self) VirtualTexture(layout, slots.first, slots.second,
                                      [&](const TileKey& k, std::uint8_t* out) {
                                          pack.read_tile(k.painting, k.level, k.tx, k.ty, out);
                                      }); },
            "pack"_a, "slots"_a = std::make_pair(30u, 30u))
        .def_prop_ro("slots", [](const VirtualTexture& vt) { return std::make_pair(vt.slots_x(), vt.slots_y()); })
        .def_prop_ro("tile_size", [](const VirtualTexture& vt) { return vt.layout().tile_size; })
        .def("insert", [](VirtualTexture& vt, const KeyTuple& key, const TileIn& data) {
            const std::size_t T = vt.layout().tile_size;
            require(data.shape(0) == T && data.shape(1) == T && data.shape(2) == 3 &&
                        data.stride(2) == 1 && data.stride(1) == 3 && data.stride(0) == std::int64_t(3 * T),
                    "tile data must be a C-contiguous (" + std::to_string(T) + ", " + std::to_string(T) +
                        ", 3) uint8 array");
            const auto ev = vt.insert(to_key(key), data.data());
            return ev ? std::optional<KeyTuple>(to_tuple(*ev)) : std::nullopt; },
            "key"_a, "data"_a, "Copies a tile into the cache; returns the evicted tile's key, if any.")
        .def("insert_loaded", [](VirtualTexture& vt, TileLoader& loader, std::size_t max) {
            std::vector<LoadedTile> results;
            std::vector<std::pair<KeyTuple, std::string>> failed;
            std::size_t inserted = 0;
            {
                nb::gil_scoped_release release;
                loader.poll(results, max);
                for (auto& r : results) {
                    if (r.buffer < 0) {
                        failed.emplace_back(to_tuple(r.key), r.error);
                        continue;
                    }
                    vt.insert(r.key, loader.data(r.buffer));
                    loader.release(r.buffer);
                    ++inserted;
                }
            }
            return std::make_pair(inserted, failed); },
            "loader"_a, "max_tiles"_a = std::size_t(-1),
            "Polls the loader and inserts its finished tiles without copies through Python; "
            "returns (inserted, [(key, error), ...]).")
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
            for (const auto& k : vt.request(to_tile_keys(keys))) out.push_back(request_of(k));
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
            const std::size_t T = vt.layout().tile_size;
            return nb::ndarray<nb::numpy, const std::uint8_t, nb::ndim<4>>(
                vt.physical(), {std::size_t(vt.slots_y()) * vt.slots_x(), T, T, 3}, nb::handle()); },
            nb::rv_policy::reference_internal,
            "The physical texture, tile-major (read-only view): [slot, y, x, rgb].")
        .def("_sample_into", [](const VirtualTexture& vt, std::uint32_t painting, const Coords& u,
                                const Coords& v, const std::optional<Lods>& lod, float lod_scalar,
                                const std::string& filter, Values out, Levels levels, unsigned threads) {
            const SampleRequest r = sample_request(painting, u, v, lod, lod_scalar, filter, out, levels, threads);
            nb::gil_scoped_release release;
            vt.sample(r); },
            "painting"_a, "u"_a, "v"_a, "lod"_a.none(), "lod_scalar"_a, "filter"_a, "out"_a,
            "levels"_a, "threads"_a);

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
            nb::rv_policy::reference_internal, "level"_a)
        .def("_sample_into", [](const MipTexture& t, const Coords& u, const Coords& v,
                                const std::optional<Lods>& lod, float lod_scalar,
                                const std::string& filter, Values out, Levels levels, unsigned threads) {
            const SampleRequest r = sample_request(0, u, v, lod, lod_scalar, filter, out, levels, threads);
            nb::gil_scoped_release release;
            t.sample(r); },
            "u"_a, "v"_a, "lod"_a.none(), "lod_scalar"_a, "filter"_a, "out"_a, "levels"_a, "threads"_a);
}

}  // namespace gigascroll::bindings
