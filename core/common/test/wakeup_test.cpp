#include "handshare/common/wakeup.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdint>
#include <thread>

#include "handshare/common/triple_buffer.hpp"
#include "handshare/testing/allocation_counter.hpp"

namespace handshare::common {
namespace {

using namespace std::chrono_literals;
using Clock = Wakeup::Clock;

TEST(Wakeup, APostBeforeTheWaitIsSeenAtOnceAndOnlyOnce) {
  Wakeup wake;
  wake.Post();
  wake.Post();  // posts while the waiter is busy coalesce
  EXPECT_TRUE(wake.WaitUntil(Clock::now() + 60s));
  // Nothing new: the next wait runs to its deadline and says so.
  EXPECT_FALSE(wake.WaitUntil(Clock::now() + 20ms));
  EXPECT_EQ(wake.posts(), 2u);
}

TEST(Wakeup, WithoutAPostTheWaitEndsAtItsDeadline) {
  Wakeup wake;
  const auto deadline = Clock::now() + 30ms;
  EXPECT_FALSE(wake.WaitUntil(deadline));
  EXPECT_GE(Clock::now(), deadline);
  EXPECT_FALSE(wake.WaitUntil(Clock::now() - 1ms));  // a deadline already passed
}

// The waiter sleeps on a one-minute deadline; a post from another thread ends the wait (true:
// only a post returns true before the deadline, and the test would otherwise take a minute).
TEST(Wakeup, APostFromAnotherThreadWakesASleepingWaiter) {
  Wakeup wake;
  std::atomic<bool> waiting{false};
  std::thread poster([&] {
    while (!waiting.load()) std::this_thread::yield();
    std::this_thread::sleep_for(20ms);  // most likely asleep in the futex by now; either way it must wake
    wake.Post();
  });
  waiting = true;
  const auto deadline = Clock::now() + 60s;
  EXPECT_TRUE(wake.WaitUntil(deadline));
  EXPECT_LT(Clock::now(), deadline);
  poster.join();
}

// The haptic thread's side allocates nothing and never blocks (run under the tsan preset too).
TEST(Wakeup, PostAllocatesNothing) {
  Wakeup wake;
  std::atomic<bool> stop{false};
  std::thread waiter([&] {
    while (!stop.load()) wake.WaitUntil(Clock::now() + 5ms);
  });
  const long before = testing::AllocationCount();
  for (int i = 0; i < 10'000; ++i) wake.Post();
  const long allocations = testing::AllocationCount() - before;
  stop = true;
  waiter.join();
  EXPECT_EQ(allocations, 0);
  EXPECT_EQ(wake.posts(), 10'000u);
}

// A producer hands values over through a triple buffer and posts after each; the consumer
// waits on the wake-up only (no polling, a deadline far away) and must see the last value: a
// post is never lost between the waiter's check and its sleep.
TEST(Wakeup, NoPostIsLostBetweenTheCheckAndTheSleep) {
  constexpr std::uint64_t kValues = 20'000;
  Wakeup wake;
  TripleBuffer<std::uint64_t> box;
  std::thread producer([&] {
    for (std::uint64_t v = 1; v <= kValues; ++v) {
      box.Write(v);
      wake.Post();
      if (v % 64 == 0) std::this_thread::yield();  // let the consumer fall asleep now and then
    }
  });
  std::uint64_t seen = 0;
  std::uint64_t value = 0;
  int wakes = 0;
  while (seen < kValues) {
    ASSERT_TRUE(wake.WaitUntil(Clock::now() + 30s)) << "a post was lost: last value seen " << seen;
    ++wakes;
    while (box.Read(value)) {
      ASSERT_GT(value, seen);
      seen = value;
    }
  }
  producer.join();
  EXPECT_EQ(seen, kValues);
  EXPECT_GT(wakes, 0);
}

}  // namespace
}  // namespace handshare::common
