#include "beslam/common/memory.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <vector>

namespace {

TEST(Memory, TouchingFiftyMegabytesRaisesTheResidentSetAndItsPeak) {
  const double before = beslam::residentMemoryMb();
  ASSERT_GT(before, 0.0);
  std::vector<char> block(50u << 20);
  std::memset(block.data(), 1, block.size());  // resident only once written
  const double during = beslam::residentMemoryMb();
  EXPECT_GT(during, before + 45.0);
  EXPECT_GE(beslam::peakResidentMemoryMb(), during - 1.0);
  EXPECT_EQ(block[block.size() / 2], 1);
}

}  // namespace
