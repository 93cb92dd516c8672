// Tile checksums: XXH3-64 over the stored bytes.
#pragma once
#include <cstddef>
#include <cstdint>

namespace gigascroll {
std::uint64_t checksum64(const void* data, std::size_t size);
}
