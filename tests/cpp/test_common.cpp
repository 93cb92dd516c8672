#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <numeric>
#include <random>
#include <set>
#include <thread>
#include <stdexcept>
#include <vector>

#include "common/checksum.h"
#include "common/divider.h"
#include "common/huge_buffer.h"
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

TEST(ParallelFor, UsesSeveralThreadsAndTheCaller) {
    // Chunks that wait for each other can only finish if two threads run them at once.
    std::atomic<int> arrived{0};
    std::mutex m;
    std::set<std::thread::id> ids;
    parallel_for(2, 1, [&](std::size_t, std::size_t) {
        {
            std::lock_guard lock(m);
            ids.insert(std::this_thread::get_id());
        }
        arrived.fetch_add(1);
        while (arrived.load() < 2) std::this_thread::yield();
    }, 2);
    EXPECT_EQ(ids.size(), 2u);
    EXPECT_TRUE(ids.count(std::this_thread::get_id()));
}

TEST(ParallelFor, NestedAndConcurrentCallsComplete) {
    // A parallel_for inside a helper and parallel_fors from several threads at once find the
    // helper pool busy and start their own threads: every index is still covered once.
    std::vector<std::atomic<int>> hits(64 * 257);
    auto nested = [&](std::size_t outer) {
        parallel_for(257, 7, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) hits[outer * 257 + i].fetch_add(1);
        }, 3);
    };
    std::vector<std::thread> callers;
    for (int c = 0; c < 4; ++c)
        callers.emplace_back([&, c] {
            parallel_for(16, 1, [&](std::size_t b, std::size_t e) {
                for (std::size_t o = b; o < e; ++o) nested(c * 16 + o);
            }, 2);
        });
    for (auto& t : callers) t.join();
    for (auto& h : hits) EXPECT_EQ(h.load(), 1);
}

TEST(ParallelFor, ManyShortCallsReuseThePool) {
    // The frame loop's pattern: thousands of small parallel calls in a row.
    std::uint64_t total = 0;
    for (int call = 0; call < 2000; ++call) {
        std::atomic<std::uint64_t> sum{0};
        parallel_for(100, 10, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) sum.fetch_add(i);
        }, 2);
        total += sum.load();
    }
    EXPECT_EQ(total, 2000u * 4950u);
}

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
        }
        // Around multiples of d, the smallest and the largest ones: where rounding errors
        // would show (the largest quotients have the largest absolute error in double).
        std::vector<std::uint64_t> qs;
        for (std::uint64_t q = 1; q < 50; ++q) qs.push_back(q);
        for (std::uint64_t q = 0xffffffffull / d; q > 0 && qs.size() < 100; --q) qs.push_back(q);
        for (std::uint64_t q : qs)
            for (std::int64_t off = -1; off <= 1; ++off) {
                const std::uint64_t n = q * d + off;
                if (n > 0xffffffffull) continue;
                ASSERT_EQ(div(std::uint32_t(n)), std::uint32_t(n / d));
                ASSERT_EQ(div.by_double(std::uint32_t(n)), std::uint32_t(n / d));
            }
    }
}

TEST(HugeBuffer, ZeroedAlignedAndReadablePastItsEnd) {
    for (std::size_t n : {std::size_t(1), std::size_t(4096), HugeBuffer::kHugePage,
                          HugeBuffer::kHugePage + 3}) {
        HugeBuffer b(n);
        ASSERT_EQ(b.size(), n);
        EXPECT_EQ(reinterpret_cast<std::uintptr_t>(b.data()) % HugeBuffer::kHugePage, 0u);
        // Every byte up to the promised slack reads as zero (ASan would flag an overrun).
        std::size_t nonzero = 0;
        for (std::size_t i = 0; i < n + HugeBuffer::kSlack; ++i) nonzero += b.data()[i] != 0;
        EXPECT_EQ(nonzero, 0u);
    }
    EXPECT_EQ(HugeBuffer().data(), nullptr);
    // More than any machine has: std::bad_alloc (MemoryError in Python), not a crash.
    EXPECT_THROW(HugeBuffer(std::size_t(1) << 62), std::bad_alloc);
}

TEST(Checksum, KnownXxh3Value) {
    // XXH3_64bits of the empty input is the published constant 0x2D06800538D394C2.
    EXPECT_EQ(checksum64("", 0), 0x2D06800538D394C2ull);
    EXPECT_NE(checksum64("a", 1), checksum64("b", 1));
}
