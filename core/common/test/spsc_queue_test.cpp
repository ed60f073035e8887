#include "handshare/common/spsc_queue.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

namespace handshare::common {
namespace {

TEST(SpscQueue, FifoAndFullAndEmpty) {
  SpscQueue<int, 4> q;
  int out = 0;
  EXPECT_FALSE(q.Pop(out));
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(q.Push(i));
  EXPECT_FALSE(q.Push(99));  // full: refused, nothing overwritten
  for (int i = 0; i < 4; ++i) {
    ASSERT_TRUE(q.Pop(out));
    EXPECT_EQ(out, i);
  }
  EXPECT_FALSE(q.Pop(out));
}

TEST(SpscQueue, ConcurrentDeliversEveryItemInOrder) {
  SpscQueue<std::uint64_t, 64> q;
  constexpr std::uint64_t kCount = 200000;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < kCount;) {
      if (q.Push(i)) ++i;
    }
  });
  std::uint64_t expected = 0, out = 0, wrong = 0;
  while (expected < kCount) {
    if (q.Pop(out)) {
      wrong += (out != expected);
      ++expected;
    }
  }
  producer.join();
  EXPECT_EQ(wrong, 0u);
}

}  // namespace
}  // namespace handshare::common
