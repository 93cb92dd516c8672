// LockedQueue under one and several producers, and its blocking wait_pop.
#include <gtest/gtest.h>

#include <cstdint>
#include <thread>
#include <vector>

#include "concurrency/locked_queue.h"
#include "concurrency/queue_stress.h"

using namespace gigascroll;

TEST(QueueStress, LockedExactlyOnceInOrder) { spsc_stress<LockedQueue<std::uint64_t>>(kStressItems / 4); }
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
