// Request processing reads the runtime's page table through the ResidencyLookup interface.
//
// Two 64-bit encodings of one tile exist on purpose, and this is the one place that converts:
//   request key (request.h): p << 37 | l << 32 | morton(x, y); seed 000's B widened, hashed by
//     the feedback/processing stages (Morton order keeps neighbouring tiles in nearby keys);
//   TileKey::packed (vt_layout.h): p << 48 | l << 40 | y << 20 | x; the runtime's total order
//     for the loader, cache and page table.
// Both name (painting, level, x, y); the request key's 16-bit tile coordinates are the limit.
#pragma once
#include "vt/request.h"
#include "vt/residency.h"
#include "vt/virtual_texture.h"

namespace gigascroll {

inline TileKey tile_key_of(std::uint64_t request) {
    const Request r = unpack_request(request);
    return TileKey{r.painting, r.level, r.x, r.y};
}
inline std::uint64_t request_of(const TileKey& k) {
    return pack_request(k.painting, k.level, k.tx, k.ty);
}

class VirtualTextureLookup : public ResidencyLookup {
public:
    explicit VirtualTextureLookup(const VirtualTexture& vt) : vt_(vt) {}
    // One page-table read (VirtualTexture::lookup takes its shared lock).
    std::uint32_t resident_level(std::uint64_t request) const override {
        return vt_.lookup(tile_key_of(request)).level();
    }

private:
    const VirtualTexture& vt_;
};

}  // namespace gigascroll
