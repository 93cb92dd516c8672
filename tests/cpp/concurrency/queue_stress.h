// Multi-thread stress for the queues: every item arrives exactly once, in order (one
// producer) or in per-producer order (several producers).
#pragma once
#include <gtest/gtest.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <thread>
#include <vector>

namespace gigascroll {

#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
inline constexpr std::size_t kStressItems = 200'000;  // sanitizers are 5-20x slower
#else
inline constexpr std::size_t kStressItems = 2'000'000;
#endif

// One producer, one consumer, mixed single and batch operations: exactly once, in order.
template <typename Q>
void spsc_stress(std::size_t n) {
    Q q(1024);
    std::thread producer([&] {
        std::vector<std::uint64_t> batch(37);
        std::uint64_t next = 0;
        while (next < n) {
            // On a full queue, yield: the machine may have fewer free cores than threads.
            if (next % 3 == 0) {
                if (q.try_push(next)) ++next;
                else std::this_thread::yield();
            } else {
                const std::size_t k = std::min<std::size_t>(batch.size(), n - next);
                for (std::size_t i = 0; i < k; ++i) batch[i] = next + i;
                const std::size_t pushed = q.try_push_batch(batch.begin(), k);
                next += pushed;
                if (pushed == 0) std::this_thread::yield();
            }
        }
    });
    std::uint64_t expect = 0;
    std::vector<std::uint64_t> out(53);
    bool ordered = true;
    while (expect < n) {
        std::uint64_t v;
        if (expect % 2 == 0) {
            if (q.try_pop(v)) ordered &= (v == expect++);
            else std::this_thread::yield();
        } else {
            const std::size_t k = q.try_pop_batch(out.begin(), out.size());
            for (std::size_t i = 0; i < k; ++i) ordered &= (out[i] == expect++);
            if (k == 0) std::this_thread::yield();
        }
    }
    producer.join();
    EXPECT_TRUE(ordered);
    EXPECT_EQ(expect, n);
    std::uint64_t v;
    EXPECT_FALSE(q.try_pop(v));
}

// P producers tag items with their id; the consumer checks per-producer order and counts.
template <typename Q>
void mpsc_stress(std::size_t producers, std::size_t per_producer) {
    Q q(512);
    std::vector<std::thread> threads;
    for (std::size_t p = 0; p < producers; ++p) {
        threads.emplace_back([&, p] {
            std::vector<std::uint64_t> batch(16);
            std::uint64_t i = 0;
            while (i < per_producer) {
                if (i % 5 == 0) {
                    if (q.try_push((std::uint64_t(p) << 40) | i)) ++i;
                    else std::this_thread::yield();
                } else {
                    const std::size_t k = std::min<std::size_t>(batch.size(), per_producer - i);
                    for (std::size_t j = 0; j < k; ++j) batch[j] = (std::uint64_t(p) << 40) | (i + j);
                    const std::size_t pushed = q.try_push_batch(batch.begin(), k);
                    i += pushed;
                    if (pushed == 0) std::this_thread::yield();
                }
            }
        });
    }
    std::vector<std::uint64_t> next(producers, 0);
    std::size_t total = 0;
    bool ordered = true;
    std::vector<std::uint64_t> out(64);
    while (total < producers * per_producer) {
        const std::size_t k = q.try_pop_batch(out.begin(), out.size());
        for (std::size_t i = 0; i < k; ++i) {
            const std::size_t p = out[i] >> 40;
            const std::uint64_t seq = out[i] & ((std::uint64_t(1) << 40) - 1);
            ordered &= p < producers && seq == next[p];
            if (p < producers) next[p] = seq + 1;
        }
        total += k;
        if (k == 0) std::this_thread::yield();
        std::uint64_t v;
        if (q.try_pop(v)) {
            const std::size_t p = v >> 40;
            ordered &= p < producers && (v & ((std::uint64_t(1) << 40) - 1)) == next[p];
            if (p < producers) ++next[p];
            ++total;
        }
    }
    for (auto& t : threads) t.join();
    EXPECT_TRUE(ordered);
    EXPECT_EQ(total, producers * per_producer);
    for (std::size_t p = 0; p < producers; ++p) EXPECT_EQ(next[p], per_producer);
    std::uint64_t v;
    EXPECT_FALSE(q.try_pop(v));
}

}  // namespace gigascroll
