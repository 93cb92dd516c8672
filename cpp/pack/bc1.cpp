#include "pack/bc1.h"

#include <squish.h>

#include <cstring>

#include "common/error.h"

namespace gigascroll {

Bc1Fit parse_bc1_fit(const std::string& name) {
    if (name == "range") return Bc1Fit::Range;
    if (name == "cluster") return Bc1Fit::Cluster;
    throw InvalidArgument("bc1 fit must be 'range' or 'cluster', got '" + name + "'");
}

void bc1_decode_tile(const std::uint8_t* blocks, std::uint32_t tile_size, std::uint8_t* rgb) {
    const std::uint32_t n = tile_size / 4;
    for (std::uint32_t by = 0; by < n; ++by)
        for (std::uint32_t bx = 0; bx < n; ++bx) {
            const std::uint8_t* block = blocks + (std::size_t(by) * n + bx) * kBc1BlockBytes;
            std::uint32_t palette[4];
            bc1_palette(block, palette);
            for (unsigned py = 0; py < 4; ++py) {
                std::uint8_t* row = rgb + ((std::size_t(by) * 4 + py) * tile_size + bx * 4) * 3;
                for (unsigned px = 0; px < 4; ++px) {
                    const std::uint32_t c = palette[(block[4 + py] >> (2 * px)) & 3u];
                    row[3 * px] = std::uint8_t(c), row[3 * px + 1] = std::uint8_t(c >> 8),
                    row[3 * px + 2] = std::uint8_t(c >> 16);
                }
            }
        }
}

void bc1_encode_tile(const std::uint8_t* rgb, std::uint32_t tile_size, std::uint8_t* blocks,
                     Bc1Fit fit) {
    const int flags = squish::kDxt1 | (fit == Bc1Fit::Cluster ? squish::kColourClusterFit
                                                              : squish::kColourRangeFit);
    const std::uint32_t n = tile_size / 4;
    squish::u8 rgba[16 * 4];
    for (std::uint32_t by = 0; by < n; ++by)
        for (std::uint32_t bx = 0; bx < n; ++bx) {
            for (unsigned py = 0; py < 4; ++py)
                for (unsigned px = 0; px < 4; ++px) {
                    const std::uint8_t* t = rgb + ((std::size_t(by) * 4 + py) * tile_size + bx * 4 + px) * 3;
                    squish::u8* o = rgba + (py * 4 + px) * 4;
                    o[0] = t[0], o[1] = t[1], o[2] = t[2], o[3] = 255;
                }
            squish::Compress(rgba, blocks + (std::size_t(by) * n + bx) * kBc1BlockBytes, flags);
        }
}

}  // namespace gigascroll
