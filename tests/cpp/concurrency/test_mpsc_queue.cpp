// MpscQueue under several producer threads.
#include <gtest/gtest.h>

#include <cstdint>

#include "concurrency/mpsc_queue.h"
#include "concurrency/queue_stress.h"

using namespace gigascroll;

TEST(QueueStress, MpscExactlyOncePerProducerOrder) {
    mpsc_stress<MpscQueue<std::uint64_t>>(4, kStressItems / 4);
}
