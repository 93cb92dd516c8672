// Queue semantics (single thread) and multi-thread stress: every item arrives exactly
// once, in order (SPSC) or in per-producer order (MPSC).
#include <gtest/gtest.h>

#include <memory>
#include <thread>
#include <vector>

#include "concurrency/locked_queue.h"
#include "concurrency/mpsc_queue.h"
#include "concurrency/spsc_queue.h"

using namespace gigascroll;

namespace {

#if defined(__SANITIZE_THREAD__) || defined(__SANITIZE_ADDRESS__)
constexpr std::size_t kStressItems = 200'000;  // sanitizers are 5-20x slower
#else
constexpr std::size_t kStressItems = 2'000'000;
#endif

// Counts live instances so tests can check every element is destroyed exactly once.
struct Tracked {
    static inline int live = 0;
    int value = -1;
    bool moved_from = false;
    Tracked() { ++live; }
    explicit Tracked(int v) : value(v) { ++live; }
    Tracked(const Tracked& o) : value(o.value) { ++live; }
    Tracked(Tracked&& o) noexcept : value(o.value) { o.moved_from = true; ++live; }
    Tracked& operator=(Tracked&& o) noexcept { value = o.value; o.moved_from = true; return *this; }
    Tracked& operator=(const Tracked& o) { value = o.value; return *this; }
    ~Tracked() { --live; }
};

template <typename Q>
class QueueTest : public ::testing::Test {};
using QueueTypes = ::testing::Types<SpscQueue<int>, MpscQueue<int>, LockedQueue<int>>;
TYPED_TEST_SUITE(QueueTest, QueueTypes);

}  // namespace

TYPED_TEST(QueueTest, FullEmptyAndWrapAround) {
    TypeParam q(4);
    int out = 0;
    EXPECT_FALSE(q.try_pop(out));
    for (int lap = 0; lap < 5; ++lap) {  // several laps over the ring
        for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.try_push(lap * 10 + i));
        EXPECT_FALSE(q.try_push(99)) << "a full queue must refuse";
        for (int i = 0; i < 4; ++i) {
            ASSERT_TRUE(q.try_pop(out));
            EXPECT_EQ(out, lap * 10 + i);
        }
        EXPECT_FALSE(q.try_pop(out));
        EXPECT_TRUE(q.try_push(lap));  // off-by-one position in the ring each lap
        ASSERT_TRUE(q.try_pop(out));
        EXPECT_EQ(out, lap);
    }
}

TYPED_TEST(QueueTest, BatchesRespectCapacityAndOrder) {
    TypeParam q(8);
    std::vector<int> in(20);
    for (int i = 0; i < 20; ++i) in[i] = i;
    EXPECT_EQ(q.try_push_batch(in.begin(), 5), 5u);
    EXPECT_EQ(q.try_push_batch(in.begin() + 5, 15), 3u) << "only the free room is filled";
    EXPECT_EQ(q.try_push_batch(in.begin(), 1), 0u);
    std::vector<int> out(20, -1);
    EXPECT_EQ(q.try_pop_batch(out.begin(), 6), 6u);
    EXPECT_EQ(q.try_push_batch(in.begin() + 8, 12), 6u);
    EXPECT_EQ(q.try_pop_batch(out.begin() + 6, 20), 8u);
    for (int i = 0; i < 14; ++i) EXPECT_EQ(out[i], i);
    EXPECT_EQ(q.try_pop_batch(out.begin(), 3), 0u);
}

template <typename Q>
static void check_destroyed_once() {
    Tracked::live = 0;
    {
        Q q(8);
        for (int i = 0; i < 6; ++i) ASSERT_TRUE(q.try_push(Tracked(i)));
        EXPECT_EQ(Tracked::live, 6);
        Tracked t;
        ASSERT_TRUE(q.try_pop(t));
        EXPECT_EQ(t.value, 0);
        EXPECT_EQ(Tracked::live, 6);  // 5 queued + t
        std::vector<Tracked> v(2);
        EXPECT_EQ(q.try_pop_batch(v.begin(), 2), 2u);
        EXPECT_EQ(v[1].value, 2);
        EXPECT_EQ(Tracked::live, 6);  // 3 queued + t + v[2]
    }  // the queue destroys what it still holds
    EXPECT_EQ(Tracked::live, 0);
}

TEST(Queues, NonTrivialElementsDestroyedExactlyOnce) {
    check_destroyed_once<SpscQueue<Tracked>>();
    check_destroyed_once<MpscQueue<Tracked>>();
    check_destroyed_once<LockedQueue<Tracked>>();
}

template <typename Q>
static void check_move_only() {
    Q q(4);
    ASSERT_TRUE(q.try_push(std::make_unique<int>(7)));
    std::unique_ptr<int> p;
    ASSERT_TRUE(q.try_pop(p));
    ASSERT_TRUE(p);
    EXPECT_EQ(*p, 7);
    ASSERT_TRUE(q.try_push(std::make_unique<int>(8)));  // left in the queue: freed by it (ASan)
}

TEST(Queues, MoveOnlyElements) {
    check_move_only<SpscQueue<std::unique_ptr<int>>>();
    check_move_only<MpscQueue<std::unique_ptr<int>>>();
    check_move_only<LockedQueue<std::unique_ptr<int>>>();
}

TEST(Queues, CapacityRoundsUpToPowerOfTwo) {
    EXPECT_EQ(SpscQueue<int>(5).capacity(), 8u);
    EXPECT_EQ(MpscQueue<int>(1).capacity(), 2u);
    EXPECT_EQ(LockedQueue<int>(5).capacity(), 5u);
}

// One producer, one consumer, mixed single and batch operations: exactly once, in order.
template <typename Q>
static void spsc_stress(std::size_t n) {
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

TEST(QueueStress, SpscExactlyOnceInOrder) { spsc_stress<SpscQueue<std::uint64_t>>(kStressItems); }
TEST(QueueStress, LockedExactlyOnceInOrder) { spsc_stress<LockedQueue<std::uint64_t>>(kStressItems / 4); }

// P producers tag items with their id; the consumer checks per-producer order and counts.
template <typename Q>
static void mpsc_stress(std::size_t producers, std::size_t per_producer) {
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

TEST(QueueStress, MpscExactlyOncePerProducerOrder) {
    mpsc_stress<MpscQueue<std::uint64_t>>(4, kStressItems / 4);
}
TEST(QueueStress, LockedMultiProducerPerProducerOrder) {
    mpsc_stress<LockedQueue<std::uint64_t>>(3, kStressItems / 12);
}

TEST(LockedQueue, WaitPopWakesOnCloseAndOnPush) {
    LockedQueue<int> q(4);
    std::thread t([&] {
        int v;
        std::vector<int> got;
        while (q.wait_pop(v)) got.push_back(v);
        EXPECT_EQ(got.size(), 3u);
    });
    for (int i = 0; i < 3; ++i)
        while (!q.try_push(i)) std::this_thread::yield();
    while (!q.empty()) std::this_thread::yield();
    q.close();
    t.join();
}
