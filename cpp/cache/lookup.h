// Request processing reads the runtime's page table through the ResidencyLookup interface.
#pragma once
#include "views/residency.h"
#include "cache/virtual_texture.h"

namespace gigascroll {

class VirtualTextureLookup : public ResidencyLookup {
public:
    explicit VirtualTextureLookup(const VirtualTexture& vt) : vt_(vt) {}
    // One page-table read (VirtualTexture::lookup takes its shared lock).
    std::uint32_t resident_level(std::uint64_t request) const override {
        return vt_.lookup(unpack_request(request)).level();
    }

private:
    const VirtualTexture& vt_;
};

}  // namespace gigascroll
