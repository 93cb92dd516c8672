// What the three queues have in common, checked on each: single-thread semantics (full,
// empty, wrap-around, batches), element lifetimes, move-only elements and capacity.
#include <gtest/gtest.h>

#include <memory>
#include <vector>

#include "concurrency/locked_queue.h"
#include "concurrency/mpsc_queue.h"
#include "concurrency/spsc_queue.h"

using namespace gigascroll;

namespace {

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
