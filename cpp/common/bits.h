// Power-of-two arithmetic shared by the queues (ring sizes), the pack geometry (page-table
// sizes) and the page-table layout: the one place these helpers live.
#pragma once
#include <bit>
#include <concepts>

namespace gigascroll {

// Smallest power of two >= v; 1 for v = 0. v must not exceed the type's largest power of two.
template <std::unsigned_integral T>
constexpr T next_pow2(T v) {
    return v <= 1 ? T(1) : std::bit_ceil(v);
}

template <std::unsigned_integral T>
constexpr bool is_pow2(T v) {
    return std::has_single_bit(v);
}

}  // namespace gigascroll
