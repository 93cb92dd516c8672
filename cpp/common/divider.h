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
    // The same quotient from two 32 x 32 -> 64-bit products, for loops meant to vectorise
    // (no vector unit has the 64 x 64 -> 128-bit product): with m = hi 2^32 + lo,
    // floor(n m / 2^64) = floor((n hi + floor(n lo / 2^32)) / 2^32), and the sum < 2^64.
    std::uint32_t by_halves(std::uint32_t n) const {
        // 32-bit halves, so the vectoriser sees widening 32 x 32 multiplies (vpmuludq).
        const auto hi = static_cast<std::uint32_t>(m_ >> 32), lo = static_cast<std::uint32_t>(m_);
        const std::uint64_t q =
            (std::uint64_t(n) * hi + ((std::uint64_t(n) * lo) >> 32)) >> 32;
        return d_ > 1 ? static_cast<std::uint32_t>(q) : n;
    }
    std::uint32_t divisor() const { return d_; }

private:
    std::uint32_t d_;
    std::uint64_t m_;
};

}  // namespace gigascroll
