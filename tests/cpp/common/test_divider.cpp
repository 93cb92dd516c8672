// Divider: multiply-and-shift and double division against the hardware divide.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "common/divider.h"

using namespace gigascroll;

TEST(Divider, MatchesHardwareDivision) {
    std::mt19937 rng(3);
    std::vector<std::uint32_t> ns = {0u, 1u, 2u, 119u, 120u, 121u, 0x7fffffffu, 0x80000000u,
                                     0xfffffffeu, 0xffffffffu};
    for (int i = 0; i < 2000; ++i) ns.push_back(rng());
    for (std::uint32_t d : {1u, 2u, 3u, 7u, 64u, 120u, 127u, 248u, 1000u, 65535u, 65536u,
                            0x7fffffffu, 0xfffffffeu, 0xffffffffu}) {
        const Divider div(d);
        EXPECT_EQ(div.divisor(), d);
        for (std::uint32_t n : ns) {
            ASSERT_EQ(div(n), n / d) << n << " / " << d;
            ASSERT_EQ(div.by_double(n), n / d) << n << " / " << d << " in double";
            if (n < 0x80000000u)
                ASSERT_EQ(div.by_double_below_2_31(std::int32_t(n)), n / d)
                    << n << " / " << d << " in double through int32";
        }
        // Around multiples of d, the smallest and the largest ones: where rounding errors
        // would show (the largest quotients have the largest absolute error in double).
        std::vector<std::uint64_t> qs;
        for (std::uint64_t q = 1; q < 50; ++q) qs.push_back(q);
        for (std::uint64_t q = 0xffffffffull / d; q > 0 && qs.size() < 100; --q) qs.push_back(q);
        // ... and the largest below 2^31 (by_double_below_2_31's range).
        for (std::uint64_t q = 0x7fffffffull / d; q > 0 && qs.size() < 150; --q) qs.push_back(q);
        for (std::uint64_t q : qs)
            for (std::int64_t off = -1; off <= 1; ++off) {
                const std::uint64_t n = q * d + off;
                if (n > 0xffffffffull) continue;
                ASSERT_EQ(div(std::uint32_t(n)), std::uint32_t(n / d));
                ASSERT_EQ(div.by_double(std::uint32_t(n)), std::uint32_t(n / d));
                if (n < 0x80000000ull)
                    ASSERT_EQ(div.by_double_below_2_31(std::int32_t(n)), std::uint32_t(n / d));
            }
    }
}
