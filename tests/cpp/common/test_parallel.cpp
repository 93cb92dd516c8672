// parallel_for: every index once, exceptions, real parallelism, nesting and pool reuse.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

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

TEST(ParallelFor, CallsTheCallerFinishesAloneLeaveThePoolUsable) {
    // Tiny calls that the caller usually finishes before the helper wakes: finish() stops
    // wanting the late helper, which must then skip that (finished) job and still take the
    // next ones. Every index covered once, in every call.
    for (int call = 0; call < 20000; ++call) {
        std::atomic<int> hits[3] = {0, 0, 0};
        parallel_for(3, 1, [&](std::size_t b, std::size_t e) {
            for (std::size_t i = b; i < e; ++i) hits[i].fetch_add(1);
        }, 2);
        ASSERT_EQ(hits[0].load() + 10 * hits[1].load() + 100 * hits[2].load(), 111) << "call " << call;
    }
}

// parallel_wavefront: second(c) only after first(c - 1 .. c + 1), on one thread and several,
// for chunk counts around the lag; and a first-pass chunk that throws late (while the other
// threads run ahead to second-pass chunks that wait for it) reaches the caller, no hang.
TEST(ParallelWavefront, SecondChunksStartAfterTheFirstChunksBesideThem) {
    for (unsigned threads : {1u, 2u, 4u})
        for (std::size_t chunks : {1u, 2u, 3u, 4u, 5u, 17u}) {
            std::vector<std::atomic<int>> first_done(chunks), second_done(chunks);
            std::atomic<int> early{0};
            parallel_wavefront(chunks, [&](std::size_t c) { first_done[c].fetch_add(1); },
                               [&](std::size_t c) {
                                   for (std::size_t d = c == 0 ? 0 : c - 1; d <= std::min(chunks - 1, c + 1); ++d)
                                       if (first_done[d].load() != 1) early.fetch_add(1);
                                   second_done[c].fetch_add(1);
                               }, threads);
            EXPECT_EQ(early.load(), 0) << threads << " threads, " << chunks << " chunks";
            for (std::size_t c = 0; c < chunks; ++c) {
                EXPECT_EQ(first_done[c].load(), 1);
                EXPECT_EQ(second_done[c].load(), 1);
            }
        }
}

TEST(ParallelWavefront, AFirstChunkThatThrowsLateReachesTheCaller) {
    for (unsigned threads : {1u, 2u, 3u}) {
        std::vector<std::atomic<int>> firsts(40);
        EXPECT_THROW(parallel_wavefront(40, [&](std::size_t c) {
            firsts[c].fetch_add(1);
            if (c == 5) {  // the others meanwhile take the next chunks, some waiting for this one
                std::this_thread::sleep_for(std::chrono::milliseconds(50));
                throw std::runtime_error("chunk 5");
            }
        }, [](std::size_t) {}, threads), std::runtime_error);
        for (const auto& f : firsts) EXPECT_LE(f.load(), 1);  // none run twice
    }
}
