// checksum64 is XXH3-64.
#include <gtest/gtest.h>

#include "common/checksum.h"

using namespace gigascroll;

TEST(Checksum, KnownXxh3Value) {
    // XXH3_64bits of the empty input is the published constant 0x2D06800538D394C2.
    EXPECT_EQ(checksum64("", 0), 0x2D06800538D394C2ull);
    EXPECT_NE(checksum64("a", 1), checksum64("b", 1));
}
