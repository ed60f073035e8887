#include "handshare/session/stream_rates.hpp"

#include <gtest/gtest.h>

namespace handshare::session {
namespace {

using namespace std::chrono_literals;
using Clock = PeerContacts::Clock;

TEST(DeviceStateRate, NobodyReadsNothingIsSent) { EXPECT_EQ(DeviceStateRate(0, 0, 0.0, 100.0), 0.0); }

TEST(DeviceStateRate, TheFastestViewersFrameRate) {
  EXPECT_DOUBLE_EQ(DeviceStateRate(2, 2, 50.0, 100.0), 50.0);
  EXPECT_DOUBLE_EQ(DeviceStateRate(1, 1, 240.0, 100.0), 100.0);  // never above the bridge's rate
  EXPECT_DOUBLE_EQ(DeviceStateRate(1, 1, 2.0, 100.0), kMinDeviceStateHz);  // the stall detection's floor
  EXPECT_DOUBLE_EQ(DeviceStateRate(1, 1, 2.0, 20.0), 20.0);                 // a bridge slower than the floor
}

TEST(DeviceStateRate, AReaderThatDidNotSayGetsEverything) {
  // Two readers, one graphics node announced: the other (a recorder) reads at the full rate.
  EXPECT_DOUBLE_EQ(DeviceStateRate(2, 1, 2.0, 100.0), 100.0);
  // A viewer that announced no rate (0) is a reader that did not say.
  EXPECT_DOUBLE_EQ(DeviceStateRate(1, 1, 0.0, 100.0), 100.0);
}

TEST(ContactSetRate, FullWhileSharedElseTheServersTick) {
  EXPECT_DOUBLE_EQ(ContactSetRate(true, 60.0, 100.0), 100.0);
  EXPECT_DOUBLE_EQ(ContactSetRate(false, 60.0, 100.0), 60.0);
  EXPECT_DOUBLE_EQ(ContactSetRate(false, 0.0, 100.0), 100.0);  // a server that did not say
  EXPECT_DOUBLE_EQ(ContactSetRate(false, 500.0, 100.0), 100.0);
}

msg::ContactSet Touching(const std::string& user, const std::string& object, int finger = 1) {
  msg::ContactSet s;
  s.user(user);
  s.fingers()[finger].active(true);
  s.fingers()[finger].object_id(object);
  return s;
}

TEST(SharesObjectWithPeer, SameObjectOnly) {
  PeerContacts peers;
  const auto t0 = Clock::now();
  const msg::ContactSet own = Touching("alice", "triceratops_tail");
  EXPECT_FALSE(SharesObjectWithPeer(own, peers, t0));  // nobody else
  peers.Receive(Touching("bob", "triceratops_head"), t0, "alice");
  EXPECT_FALSE(SharesObjectWithPeer(own, peers, t0));  // another object
  peers.Receive(Touching("carol", "triceratops_tail", 4), t0, "alice");
  EXPECT_TRUE(SharesObjectWithPeer(own, peers, t0));
  // carol's set fades out: no longer shared.
  EXPECT_FALSE(SharesObjectWithPeer(own, peers, t0 + 2s));
  // A hand touching nothing shares nothing.
  EXPECT_FALSE(SharesObjectWithPeer(msg::ContactSet{}, peers, t0));
}

TEST(SharesObjectWithPeer, InactiveFingersDoNotCountClaimsDo) {
  PeerContacts peers;
  const auto t0 = Clock::now();
  msg::ContactSet lifted = Touching("bob", "ball");
  lifted.fingers()[1].active(false);
  peers.Receive(lifted, t0, "alice");
  EXPECT_FALSE(SharesObjectWithPeer(Touching("alice", "ball"), peers, t0));
  msg::ContactSet holder;
  holder.user("bob");
  holder.simulating(true);
  holder.simulated_object_id("ball");
  peers.Receive(holder, t0, "alice");
  EXPECT_TRUE(SharesObjectWithPeer(Touching("alice", "ball"), peers, t0));
}

// Counts the sends of a pacer offered every tick of a 100 Hz bridge whose ticks jitter.
int Sends(StreamPacer& pacer, double rate_Hz, int ticks, std::uint64_t jitter_ns = 0) {
  int sent = 0;
  for (int k = 0; k < ticks; ++k) {
    const std::uint64_t now = 1'000'000'000ull + static_cast<std::uint64_t>(k) * 10'000'000ull +
                              (k % 2 == 0 ? 0 : jitter_ns);  // every other tick late
    sent += pacer.Due(now, rate_Hz) ? 1 : 0;
  }
  return sent;
}

TEST(StreamPacer, HoldsTheRateItIsGiven) {
  StreamPacer pacer(100.0);
  EXPECT_EQ(Sends(pacer, 100.0, 1000, 3'000'000), 1000);  // the tick rate: every tick, jitter or not
  pacer.Reset();
  EXPECT_NEAR(Sends(pacer, 30.0, 1000), 300, 2);
  pacer.Reset();
  EXPECT_NEAR(Sends(pacer, 60.0, 1000, 2'000'000), 600, 60);  // 10 s at 60 Hz on jittery ticks
  pacer.Reset();
  EXPECT_EQ(Sends(pacer, 0.0, 100), 0);
}

TEST(StreamPacer, ALateTickMakesNoBurst) {
  StreamPacer pacer(100.0);
  ASSERT_TRUE(pacer.Due(1'000'000'000ull, 10.0));
  // The bridge stalls for a second: one send when it is back, then the rate again.
  EXPECT_TRUE(pacer.Due(2'000'000'000ull, 10.0));
  EXPECT_FALSE(pacer.Due(2'010'000'000ull, 10.0));
  EXPECT_FALSE(pacer.Due(2'050'000'000ull, 10.0));
  EXPECT_TRUE(pacer.Due(2'100'000'000ull, 10.0));
}

}  // namespace
}  // namespace handshare::session
