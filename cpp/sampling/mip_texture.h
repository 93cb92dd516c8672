// A plain in-memory mip-mapped RGB8 texture sampled by the same filter code as the virtual
// texture, without the indirection: the baseline of the sampling benchmark and, assembled
// from a pack's tiles, an exact reference for the virtual texture in tests.
#pragma once
#include <cstdint>
#include <vector>

#include "sampling/sampler.h"

namespace gigascroll {

class TilePack;

class MipTexture {
public:
    struct Level {
        std::uint32_t width = 0, height = 0;
        std::vector<std::uint8_t> rgb;  // height x width x 3
    };
    // Level l must be ceil(W / 2^l) x ceil(H / 2^l) (InvalidArgument otherwise).
    explicit MipTexture(std::vector<Level> levels);
    // Assembles levels [0, levels) of painting p from the tiles' payloads (0 = all).
    static MipTexture from_pack(const TilePack& pack, std::uint32_t painting, std::uint32_t levels = 0);

    std::uint32_t level_count() const { return static_cast<std::uint32_t>(levels_.size()); }
    const Level& level(std::uint32_t l) const { return levels_[l]; }
    // Same semantics as VirtualTexture::sample (r.painting is ignored); level_out gets the
    // level asked for.
    void sample(const SampleRequest& r) const;

private:
    std::vector<Level> levels_;
};

}  // namespace gigascroll
