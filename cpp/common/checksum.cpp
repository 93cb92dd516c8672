#include "common/checksum.h"

#include <xxhash.h>

namespace gigascroll {
std::uint64_t checksum64(const void* data, std::size_t size) { return XXH3_64bits(data, size); }
std::uint64_t checksum64(const void* data, std::size_t size, std::uint64_t seed) {
    return XXH3_64bits_withSeed(data, size, seed);
}
}  // namespace gigascroll
