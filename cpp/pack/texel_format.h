// How the physical cache keeps a tile: RGB8 texels, or the pack's BC1 blocks as stored (decoded
// by the sampler on the fly). Decided by the pack's codec: zstd is lossless transport and
// decodes to RGB8; bc1 is a GPU format and stays block-compressed.
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>

#include "pack/bc1.h"
#include "pack/format.h"

namespace gigascroll {

enum class TexelFormat : std::uint32_t { Rgb8 = 0, Bc1 = 1 };

inline TexelFormat texel_format_of(Codec codec) {
    return codec == Codec::Bc1 ? TexelFormat::Bc1 : TexelFormat::Rgb8;
}

inline const char* texel_format_name(TexelFormat f) { return f == TexelFormat::Bc1 ? "bc1" : "rgb8"; }

// Bytes of one T x T tile in the format.
inline std::size_t texel_format_tile_bytes(TexelFormat f, std::uint32_t tile_size) {
    return f == TexelFormat::Bc1 ? bc1_tile_bytes(tile_size) : std::size_t(tile_size) * tile_size * 3;
}

// A tile as an array: (T, T, 3) RGB8 texels, or (T/4, T/4, 8) BC1 blocks.
inline std::array<std::size_t, 3> texel_format_tile_shape(TexelFormat f, std::uint32_t tile_size) {
    if (f == TexelFormat::Bc1) return {tile_size / 4u, tile_size / 4u, kBc1BlockBytes};
    return {tile_size, tile_size, 3};
}

}  // namespace gigascroll
