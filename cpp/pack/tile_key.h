// One tile of the virtual texture (painting p, mip level l, tile x, y), TileKey, and its two
// 64-bit encodings, on purpose:
//   request key: p << 37 | l << 32 | morton(x, y); VT-mobile-VR's B widened, hashed by the
//     feedback and processing stages (Morton order keeps neighbouring tiles in nearby keys);
//   TileKey::packed: p << 48 | l << 40 | y << 20 | x; the runtime's total order for the
//     loader, cache and page table.
// The request key's 16-bit tile coordinates are the joint limit.
//
// The request key:
// VT-mobile-VR packs B = p 2^28 + l 2^24 + morton(x, y) into 32 bits, which overflows past
// 16 paintings, 16 levels or 4096 tiles per axis. We widen every field:
//
//   bit 63 ............ 37 | 36 .. 32 | 31 ............. 0
//        painting p (27)   | level (5)| morton(x, y) (32): x in even bits, y in odd bits
//
// so B = p 2^37 + l 2^32 + morton(x, y), tiles up to 65535 per axis, 32 levels,
// 2^27 - 1 paintings. The all-ones key (painting 2^27 - 1) is reserved: kNoRequest marks
// feedback pixels that see no painting, and empty hash slots.
#pragma once
#include <cstdint>

namespace gigascroll {

inline constexpr std::uint64_t kNoRequest = ~std::uint64_t(0);
inline constexpr std::uint32_t kMaxPaintings = (1u << 27) - 1;
inline constexpr std::uint32_t kMaxLevels = 32;

// Interleaves the low 16 bits of x (even bits) and y (odd bits).
constexpr std::uint32_t morton2(std::uint32_t x, std::uint32_t y) {
    auto spread = [](std::uint32_t v) {
        v &= 0xFFFFu;
        v = (v | (v << 8)) & 0x00FF00FFu;
        v = (v | (v << 4)) & 0x0F0F0F0Fu;
        v = (v | (v << 2)) & 0x33333333u;
        v = (v | (v << 1)) & 0x55555555u;
        return v;
    };
    return spread(x) | (spread(y) << 1);
}

constexpr std::uint32_t morton2_x(std::uint32_t m) {
    m &= 0x55555555u;
    m = (m | (m >> 1)) & 0x33333333u;
    m = (m | (m >> 2)) & 0x0F0F0F0Fu;
    m = (m | (m >> 4)) & 0x00FF00FFu;
    m = (m | (m >> 8)) & 0x0000FFFFu;
    return m;
}
constexpr std::uint32_t morton2_y(std::uint32_t m) { return morton2_x(m >> 1); }

// A tile of the virtual texture: painting, level, tile column and row.
struct TileKey {
    std::uint32_t painting = 0, level = 0, tx = 0, ty = 0;
    // The cache key, 16 | 8 | 20 | 20 bits: a total order and a hash key in one word.
    constexpr std::uint64_t packed() const {
        return (std::uint64_t(painting) << 48) | (std::uint64_t(level) << 40) |
               (std::uint64_t(ty) << 20) | std::uint64_t(tx);
    }
    static constexpr TileKey unpack(std::uint64_t k) {
        return {std::uint32_t(k >> 48), std::uint32_t((k >> 40) & 0xFF),
                std::uint32_t(k & 0xFFFFF), std::uint32_t((k >> 20) & 0xFFFFF)};
    }
    friend bool operator==(const TileKey&, const TileKey&) = default;
};

// The request key.
constexpr std::uint64_t pack_request(std::uint32_t painting, std::uint32_t level, std::uint32_t x,
                                     std::uint32_t y) {
    return (std::uint64_t(painting) << 37) | (std::uint64_t(level & 31u) << 32) | morton2(x, y);
}
constexpr std::uint64_t pack_request(const TileKey& k) {
    return pack_request(k.painting, k.level, k.tx, k.ty);
}
constexpr TileKey unpack_request(std::uint64_t key) {
    const auto m = static_cast<std::uint32_t>(key);
    return {static_cast<std::uint32_t>(key >> 37), static_cast<std::uint32_t>(key >> 32) & 31u,
            morton2_x(m), morton2_y(m)};
}
constexpr std::uint32_t request_painting(std::uint64_t key) {
    return static_cast<std::uint32_t>(key >> 37);
}
constexpr std::uint32_t request_level(std::uint64_t key) {
    return static_cast<std::uint32_t>(key >> 32) & 31u;
}

// The tile at `level` (>= the request's level) that covers the requested tile.
constexpr std::uint64_t ancestor_request(std::uint64_t key, std::uint32_t level) {
    const TileKey k = unpack_request(key);
    const std::uint32_t up = level - k.level;
    return pack_request(k.painting, level, k.tx >> up, k.ty >> up);
}

}  // namespace gigascroll
