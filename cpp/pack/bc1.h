// BC1 (DXT1) tiles (LOD-texture's DXT, VT-mobile-VR's compressed tiles): a tile of T x T texels is
// (T/4)^2 blocks of 8 bytes, row-major over blocks, 4 bits per texel against RGB8's 24, so the
// physical cache holds exactly 6x the tiles in the same memory. Encoding is libsquish's cluster
// or cluster fit; decoding is ours, inline, so the sampler decodes the texels a footprint needs on the fly.
//
// A block: two RGB565 endpoints c0, c1 (little-endian u16) then 4 bytes of 2-bit indices, one
// byte per texel row, texel x at bits 2x. Endpoints expand to 8 bits by bit replication; with
// c0 > c1 the palette is {c0, c1, (2 c0 + c1) / 3, (c0 + 2 c1) / 3}, otherwise
// {c0, c1, (c0 + c1) / 2, black}, integer division per channel: libsquish's own decoder's
// arithmetic, so a tile decodes to the same bytes in both (tested bit for bit).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

namespace gigascroll {

inline constexpr std::size_t kBc1BlockBytes = 8;

// Bytes of a T x T tile in BC1 (T a multiple of 4).
inline constexpr std::size_t bc1_tile_bytes(std::uint32_t tile_size) {
    return std::size_t(tile_size / 4) * (tile_size / 4) * kBc1BlockBytes;
}

// Texel (px, py) in [0, 4)^2 of one block, as RGB8 into rgb[3].
inline void bc1_decode_texel(const std::uint8_t* block, unsigned px, unsigned py,
                             std::uint8_t* rgb) {
    const unsigned c0 = unsigned(block[0]) | unsigned(block[1]) << 8;
    const unsigned c1 = unsigned(block[2]) | unsigned(block[3]) << 8;
    const unsigned index = (block[4 + py] >> (2 * px)) & 3u;
    const unsigned r0 = c0 >> 11, g0 = (c0 >> 5) & 63u, b0 = c0 & 31u;
    const unsigned r1 = c1 >> 11, g1 = (c1 >> 5) & 63u, b1 = c1 & 31u;
    const unsigned a[3] = {r0 << 3 | r0 >> 2, g0 << 2 | g0 >> 4, b0 << 3 | b0 >> 2};
    const unsigned b[3] = {r1 << 3 | r1 >> 2, g1 << 2 | g1 >> 4, b1 << 3 | b1 >> 2};
    const bool four = c0 > c1;
    for (int c = 0; c < 3; ++c) {
        unsigned v;
        switch (index) {
            case 0: v = a[c]; break;
            case 1: v = b[c]; break;
            case 2: v = four ? (2 * a[c] + b[c]) / 3 : (a[c] + b[c]) / 2; break;
            default: v = four ? (a[c] + 2 * b[c]) / 3 : 0; break;
        }
        rgb[c] = static_cast<std::uint8_t>(v);
    }
}

// The block's 4 palette colours as RGB8 in the low 3 bytes of each word (r | g << 8 | b << 16),
// the same values bc1_decode_texel gives: decode once, then a texel is one index lookup.
inline void bc1_palette(const std::uint8_t* block, std::uint32_t* palette) {
    const unsigned c0 = unsigned(block[0]) | unsigned(block[1]) << 8;
    const unsigned c1 = unsigned(block[2]) | unsigned(block[3]) << 8;
    const unsigned r0 = c0 >> 11, g0 = (c0 >> 5) & 63u, b0 = c0 & 31u;
    const unsigned r1 = c1 >> 11, g1 = (c1 >> 5) & 63u, b1 = c1 & 31u;
    const unsigned a[3] = {r0 << 3 | r0 >> 2, g0 << 2 | g0 >> 4, b0 << 3 | b0 >> 2};
    const unsigned b[3] = {r1 << 3 | r1 >> 2, g1 << 2 | g1 >> 4, b1 << 3 | b1 >> 2};
    std::uint32_t p2 = 0, p3 = 0;
    if (c0 > c1) {
        for (int c = 0; c < 3; ++c)
            p2 |= ((2 * a[c] + b[c]) / 3) << (8 * c), p3 |= ((a[c] + 2 * b[c]) / 3) << (8 * c);
    } else {
        for (int c = 0; c < 3; ++c) p2 |= ((a[c] + b[c]) / 2) << (8 * c);
    }
    palette[0] = a[0] | a[1] << 8 | a[2] << 16;
    palette[1] = b[0] | b[1] << 8 | b[2] << 16;
    palette[2] = p2;
    palette[3] = p3;
}

// Texel (x, y) of a T x T BC1 tile (blocks_per_row = T / 4).
inline void bc1_tile_texel(const std::uint8_t* tile, std::uint32_t blocks_per_row,
                           std::uint32_t x, std::uint32_t y, std::uint8_t* rgb) {
    const std::uint8_t* block =
        tile + (std::size_t(y >> 2) * blocks_per_row + (x >> 2)) * kBc1BlockBytes;
    bc1_decode_texel(block, x & 3u, y & 3u, rgb);
}

// The whole tile: T x T x RGB8, row-major, into rgb.
void bc1_decode_tile(const std::uint8_t* blocks, std::uint32_t tile_size, std::uint8_t* rgb);
// libsquish's endpoint fits: Range (endpoints on the principal axis's extent: ~6 us a block
// here, the default, so a 150-gigapixel collection packs in hours, not days) or Cluster (the
// best ordering of the 16 texels along the axis: ~1.4 dB more PSNR at ~25x the time).
enum class Bc1Fit : std::uint32_t { Range = 0, Cluster = 1 };
// "range" / "cluster"; InvalidArgument otherwise.
Bc1Fit parse_bc1_fit(const std::string& name);

// Encodes a T x T x RGB8 tile into bc1_tile_bytes(T) bytes (uniform channel weights: the error
// PSNR measures). Deterministic: the same 4 x 4 texels always give the same block, which keeps
// the borders neighbouring tiles share seamless.
void bc1_encode_tile(const std::uint8_t* rgb, std::uint32_t tile_size, std::uint8_t* blocks,
                     Bc1Fit fit = Bc1Fit::Range);

}  // namespace gigascroll
