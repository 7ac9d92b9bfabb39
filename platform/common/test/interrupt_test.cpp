#include "beslam/common/interrupt.hpp"

#include <gtest/gtest.h>

#include <csignal>

#include "beslam/common/error.hpp"

namespace beslam {
namespace {

TEST(InterruptGuard, FirstSignalIsOnlyRecorded) {
  InterruptGuard guard;
  EXPECT_EQ(InterruptGuard::requested(), 0);
  std::raise(SIGTERM);
  EXPECT_EQ(InterruptGuard::requested(), SIGTERM);
  EXPECT_EQ(signalName(InterruptGuard::requested()), "SIGTERM");
}

TEST(InterruptGuard, EachGuardStartsClear) {
  {
    InterruptGuard guard;
    std::raise(SIGINT);
    EXPECT_EQ(InterruptGuard::requested(), SIGINT);
  }
  InterruptGuard again;
  EXPECT_EQ(InterruptGuard::requested(), 0);
}

TEST(InterruptGuard, OnlyOneAtATime) {
  InterruptGuard guard;
  EXPECT_THROW(InterruptGuard second, Error);
}

TEST(InterruptGuardDeathTest, SecondSignalEndsTheProcessAtOnce) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        InterruptGuard guard;
        std::raise(SIGINT);
        std::raise(SIGINT);
        std::exit(0);  // not reached
      },
      ::testing::KilledBySignal(SIGINT), "");
}

TEST(InterruptGuardDeathTest, PreviousHandlerIsBackAfterTheGuard) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        { InterruptGuard guard; }
        std::raise(SIGTERM);  // the default action again
        std::exit(0);
      },
      ::testing::KilledBySignal(SIGTERM), "");
}

}  // namespace
}  // namespace beslam
