// SpscQueue under one producer and one consumer thread.
#include <gtest/gtest.h>

#include <cstdint>

#include "concurrency/spsc_queue.h"
#include "concurrency/queue_stress.h"

using namespace gigascroll;

TEST(QueueStress, SpscExactlyOnceInOrder) { spsc_stress<SpscQueue<std::uint64_t>>(kStressItems); }
