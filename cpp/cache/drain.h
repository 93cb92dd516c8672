// The frame's drain stage: finished tiles move from the loader's buffers into the physical
// cache without passing through Python, and every buffer goes back to the loader.
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "loading/tile_loader.h"
#include "cache/virtual_texture.h"

namespace gigascroll {

struct DrainResult {
    std::vector<std::uint64_t> arrived;                  // request keys of every tile back
    std::vector<std::pair<TileKey, std::string>> failed; // loads that failed, with the reason
    std::size_t inserted = 0;
};

// Polls up to max_tiles finished tiles and inserts the loaded ones into vt. Every polled
// buffer is released and every polled tile is in `arrived`; a tile whose insert fails is
// reported in `failed` with the reason (the batch goes on). InvalidArgument, before anything
// is polled, when the loader reads another pack than the one vt was built from.
DrainResult drain(TileLoader& loader, VirtualTexture& vt, std::size_t max_tiles);

}  // namespace gigascroll
