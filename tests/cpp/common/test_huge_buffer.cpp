// HugeBuffer: zeroed, huge-page aligned, readable slack past the end, bad_alloc when too big.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <new>

#include "common/huge_buffer.h"

using namespace gigascroll;

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
