// Division of 32-bit unsigned integers by a divisor fixed at run time, as a multiply
// (Granlund and Montgomery 1994): with m = floor(2^64 / d) + 1, floor(n m / 2^64) = n / d
// for every n < 2^32 and 1 < d < 2^32. A hardware 32-bit div costs ~26 cycles; the tile
// size is fixed per pack, and per-pixel tile coordinates were the hot loops' largest cost.
#pragma once
#include <cstdint>

namespace gigascroll {

class Divider {
public:
    explicit Divider(std::uint32_t d = 1)
        : d_(d), m_(d > 1 ? ~std::uint64_t(0) / d + 1 : 0), inv_(1.0 / d) {}
    std::uint32_t operator()(std::uint32_t n) const {
        return d_ > 1 ? static_cast<std::uint32_t>((unsigned __int128)n * m_ >> 64) : n;
    }
    // The same quotient in double arithmetic, for loops meant to vectorise (a vector
    // 64 x 64-bit multiply is slow or missing): q' = (n + 1/2) * fl(1/d) is within
    // 2^-52 (n + 1/2) / d < 2^-20 / d of (n + 1/2) / d, whose distance to the nearest
    // integer is at least 1/(2d), so floor(q') = floor(n / d) for every 32-bit n and d.
    std::uint32_t by_double(std::uint32_t n) const {
        return static_cast<std::uint32_t>((double(n) + 0.5) * inv_);
    }
    // by_double for 0 <= n < 2^31 through int32 conversions (x86 has SIMD int32 <-> double
    // but no uint32 <-> double below AVX-512, which GCC emulates at several instructions
    // each): the same double, the same quotient (below 2^31), so the same result.
    std::uint32_t by_double_below_2_31(std::int32_t n) const {
        return static_cast<std::uint32_t>(static_cast<std::int32_t>((double(n) + 0.5) * inv_));
    }
    std::uint32_t divisor() const { return d_; }
    // fl(1 / d), by_double's factor (for SIMD lanes doing the same arithmetic).
    double inverse() const { return inv_; }

private:
    std::uint32_t d_;
    std::uint64_t m_;
    double inv_;
};

}  // namespace gigascroll
