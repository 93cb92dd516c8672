// Tile checksums: XXH3-64 over the stored bytes.
#pragma once
#include <cstddef>
#include <cstdint>

namespace gigascroll {
std::uint64_t checksum64(const void* data, std::size_t size);
// XXH3-64 with a seed (a pack v2 tile's key: the checksum then names the tile it belongs to).
std::uint64_t checksum64(const void* data, std::size_t size, std::uint64_t seed);
}
