#include "handshare/common/triple_buffer.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdint>
#include <thread>

namespace handshare::common {
namespace {

struct Snapshot {
  std::uint64_t seq;
  std::uint64_t payload[15];  // every word equals seq: a torn read would mix values
};

TEST(TripleBuffer, ReadsNothingBeforeFirstPublish) {
  TripleBuffer<int> buffer;
  int out = 7;
  EXPECT_FALSE(buffer.Read(out));
  EXPECT_EQ(out, 7);
}

TEST(TripleBuffer, ReadsNewestValueOnce) {
  TripleBuffer<int> buffer;
  buffer.Write(1);
  buffer.Write(2);
  buffer.Write(3);
  int out = 0;
  ASSERT_TRUE(buffer.Read(out));
  EXPECT_EQ(out, 3);
  EXPECT_FALSE(buffer.Read(out));  // nothing newer
  buffer.Write(4);
  ASSERT_TRUE(buffer.Read(out));
  EXPECT_EQ(out, 4);
}

// Producer and consumer on two threads (run under the tsan preset too): the consumer must
// never see a torn snapshot and the sequence it sees must never go backwards.
TEST(TripleBuffer, ConcurrentHandOffIsNeverTornAndMonotonic) {
  TripleBuffer<Snapshot> buffer;
  constexpr std::uint64_t kCount = 200000;
  std::thread producer([&] {
    for (std::uint64_t i = 1; i <= kCount; ++i) {
      Snapshot& s = buffer.WriteSlot();
      s.seq = i;
      for (auto& w : s.payload) w = i;
      buffer.Publish();
    }
  });
  // The last Publish() leaves a fresh value, so the consumer always reaches kCount.
  std::uint64_t last = 0, reads = 0, torn = 0, backwards = 0;
  Snapshot s{};
  while (last != kCount) {
    if (!buffer.Read(s)) continue;
    ++reads;
    for (auto w : s.payload) torn += (w != s.seq);
    backwards += (s.seq < last);
    last = s.seq;
  }
  producer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kCount);  // the final value is always delivered
  EXPECT_GT(reads, 0u);
}

}  // namespace
}  // namespace handshare::common
