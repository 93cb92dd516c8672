// loading/: the asynchronous tile loader and the loading strategies.
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

#include "loading/load_strategy.h"
#include "loading/tile_loader.h"
#include "pack/reader.h"

namespace nb = nanobind;
using namespace nb::literals;

namespace gigascroll::bindings {
namespace {
using Tile = nb::ndarray<nb::numpy, std::uint8_t, nb::ndim<3>>;
// A finished tile in the cache's form (RGB8 texels or a bc1 pack's blocks).
Tile new_tile(const TilePack& pack, const std::uint8_t* src) {
    const auto shape = texel_format_tile_shape(pack.slot_format(), pack.tile_size());
    FreshArray<std::uint8_t, nb::ndim<3>> tile({shape[0], shape[1], shape[2]});
    std::memcpy(tile.data, src, pack.slot_bytes());
    return tile.array;
}

}  // namespace

void bind_loading(nb::module_& m) {
    nb::class_<TileLoader>(m, "TileLoader",
        "Asynchronous tile loading: 'lockfree' (SPSC command queues, MPSC result queue, the seed's "
        "design) or 'locked' (mutex job queue and result list, the Unreal-style baseline).")
        .def("__init__", [](TileLoader* self, const TilePack& pack, const std::string& mode,
                            unsigned threads, std::size_t queue_capacity, std::size_t pool_tiles) {
            LoaderOptions o;
            o.queue_capacity = queue_capacity;
            o.pool_tiles = pool_tiles;
            new (self) TileLoader(pack, parse_loader_mode(mode), threads, o); },
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
            // Every buffer goes back to the loader, also when a copy fails (MemoryError).
            std::size_t next = 0;
            try {
                nb::list out;
                for (; next < results.size(); ++next) {
                    const LoadedTile& r = results[next];
                    if (r.buffer >= 0) {
                        out.append(nb::make_tuple(to_tuple(r.key), new_tile(l.pack(), l.data(r.buffer))));
                        l.release(r.buffer);
                    } else {
                        out.append(nb::make_tuple(to_tuple(r.key), r.error));
                    }
                }
                return out;
            } catch (...) {
                for (; next < results.size(); ++next)
                    if (results[next].buffer >= 0) l.release(results[next].buffer);
                throw;
            } }, "max_tiles"_a)
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
            return std::string(loader_mode_name(l.mode())); })
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

    nb::class_<DirectLoading>(m, "DirectLoading",
                              "VT-mobile-VR: load missing requested tiles, at most per_frame a frame.")
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

}

}  // namespace gigascroll::bindings
