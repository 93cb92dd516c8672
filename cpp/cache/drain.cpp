#include "cache/drain.h"

#include <exception>

#include "common/error.h"
#include "cache/lookup.h"

namespace gigascroll {

DrainResult drain(TileLoader& loader, VirtualTexture& vt, std::size_t max_tiles) {
    require(loader.tile_bytes() == vt.slot_bytes(),
            "drain: the loader's tiles are not the size of the virtual texture's slots (a bc1 "
            "pack's loader delivers BC1 blocks: build the VirtualTexture from that pack)");
    std::vector<LoadedTile> results;
    loader.poll(results, max_tiles);
    DrainResult out;
    out.arrived.reserve(results.size());
    std::exception_ptr error;
    for (LoadedTile& r : results) {
        out.arrived.push_back(pack_request(r.key));
        if (r.buffer < 0) {
            out.failed.emplace_back(r.key, std::move(r.error));
            continue;
        }
        if (!error) {
            try {
                vt.insert(r.key, loader.data(r.buffer));
                ++out.inserted;
            } catch (...) {
                error = std::current_exception();
            }
        }
        loader.release(r.buffer);
    }
    if (error) std::rethrow_exception(error);
    return out;
}

}  // namespace gigascroll
