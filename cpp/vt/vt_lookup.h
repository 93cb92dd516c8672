// Request processing reads the runtime's page table through the ResidencyLookup interface.
#pragma once
#include "vt/request.h"
#include "vt/residency.h"
#include "vt/virtual_texture.h"

namespace gigascroll {

class VirtualTextureLookup : public ResidencyLookup {
public:
    explicit VirtualTextureLookup(const VirtualTexture& vt) : vt_(vt) {}
    // One page-table read (VirtualTexture::lookup takes its shared lock).
    std::uint32_t resident_level(std::uint64_t request) const override {
        const Request r = unpack_request(request);
        return vt_.lookup(TileKey{r.painting, r.level, r.x, r.y}).level();
    }

private:
    const VirtualTexture& vt_;
};

}  // namespace gigascroll
