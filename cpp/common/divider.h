// Division of 32-bit unsigned integers by a divisor fixed at run time, as a multiply
// (Granlund and Montgomery 1994): with m = floor(2^64 / d) + 1, floor(n m / 2^64) = n / d
// for every n < 2^32 and 1 < d < 2^32. A hardware 32-bit div costs ~26 cycles; the tile
// size is fixed per pack, and per-pixel tile coordinates were the hot loops' largest cost.
#pragma once
#include <cstdint>

namespace gigascroll {

class Divider {
public:
    explicit Divider(std::uint32_t d = 1) : d_(d), m_(d > 1 ? ~std::uint64_t(0) / d + 1 : 0) {}
    std::uint32_t operator()(std::uint32_t n) const {
        return d_ > 1 ? static_cast<std::uint32_t>((unsigned __int128)n * m_ >> 64) : n;
    }
    std::uint32_t divisor() const { return d_; }

private:
    std::uint32_t d_;
    std::uint64_t m_;
};

}  // namespace gigascroll
