#include "cache/drain.h"

#include <algorithm>
#include <exception>
#include <string>

#include "common/error.h"
#include "cache/lookup.h"
#include "pack/reader.h"

namespace gigascroll {

DrainResult drain(TileLoader& loader, VirtualTexture& vt, std::size_t max_tiles) {
    require(loader.tile_bytes() == vt.slot_bytes(),
            "drain: the loader's tiles are not the size of the virtual texture's slots (a bc1 "
            "pack's loader delivers BC1 blocks: build the VirtualTexture from that pack)");
    require(vt.pack_fingerprint() == 0 || vt.pack_fingerprint() == loader.pack_fingerprint(),
            "drain: the loader reads another pack than the one the virtual texture was built from");
    DrainResult out;
    std::vector<LoadedTile> results;
    // Reserved before the poll: once tiles are polled nothing may throw before every buffer
    // is back, or its tile would be lost and the buffer leaked.
    results.reserve(std::min<std::size_t>(max_tiles, 1u << 16));
    loader.poll(results, max_tiles);
    out.arrived.reserve(results.size());
    out.failed.reserve(results.size());
    for (LoadedTile& r : results) {
        out.arrived.push_back(pack_request(r.key));
        if (r.buffer < 0) {
            out.failed.emplace_back(r.key, std::move(r.error));
            continue;
        }
        // A tile that cannot be inserted is reported with the failed loads: the batch goes
        // on, every buffer goes back, and the caller sees every tile that arrived.
        try {
            vt.insert(r.key, loader.data(r.buffer));
            ++out.inserted;
        } catch (const std::exception& e) {
            out.failed.emplace_back(r.key, std::string("insert: ") + e.what());
        }
        loader.release(r.buffer);
    }
    return out;
}

}  // namespace gigascroll
