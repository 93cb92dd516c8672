#include <gtest/gtest.h>

#include <atomic>
#include <numeric>
#include <stdexcept>
#include <vector>

#include "common/checksum.h"
#include "common/parallel.h"

using namespace gigascroll;

TEST(ParallelFor, CoversEveryIndexOnce) {
    std::vector<std::atomic<int>> hits(10007);
    parallel_for(hits.size(), 13, [&](std::size_t b, std::size_t e) {
        for (std::size_t i = b; i < e; ++i) hits[i].fetch_add(1);
    }, 4);
    for (auto& h : hits) EXPECT_EQ(h.load(), 1);
}

TEST(ParallelFor, RethrowsWorkerException) {
    EXPECT_THROW(parallel_for(1000, 1, [](std::size_t b, std::size_t) {
        if (b == 517) throw std::runtime_error("boom");
    }, 2), std::runtime_error);
}

TEST(Checksum, KnownXxh3Value) {
    // XXH3_64bits of the empty input is the published constant 0x2D06800538D394C2.
    EXPECT_EQ(checksum64("", 0), 0x2D06800538D394C2ull);
    EXPECT_NE(checksum64("a", 1), checksum64("b", 1));
}
