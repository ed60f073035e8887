// The session clock: every node runs periodic motions on the world server's origin, through
// its own steady clock, so the phase neither jumps at midnight UTC nor when the wall clock is
// stepped.
#include "handshare/common/session_clock.hpp"

#include <gtest/gtest.h>

namespace handshare::common {
namespace {

constexpr std::uint64_t kSecond = 1'000'000'000ULL;
// 23:59:50 UTC on 2026-12-01, as Unix time.
constexpr std::uint64_t kBeforeMidnight = 1'796'169'590ULL * kSecond;

TEST(SessionClock, TwoHostsWithDifferentSteadyClocksAgreeOnTheSessionTime) {
  const std::uint64_t epoch = kBeforeMidnight - 100 * kSecond;  // the server started 100 s ago
  // Host A booted long ago, host B recently: their steady clocks differ by hours.
  const SessionClock a = SessionClock::FromEpoch(epoch, kBeforeMidnight, 9'000 * kSecond);
  const SessionClock b = SessionClock::FromEpoch(epoch, kBeforeMidnight, 20 * kSecond);
  EXPECT_DOUBLE_EQ(a.At_s(9'000 * kSecond), 100.0);
  EXPECT_DOUBLE_EQ(b.At_s(20 * kSecond), 100.0);
  EXPECT_DOUBLE_EQ(a.At_s(9'003 * kSecond), b.At_s(23 * kSecond));
}

TEST(SessionClock, ThePhaseRunsOnThroughMidnightUtc) {
  const SessionClock c = SessionClock::FromEpoch(kBeforeMidnight, kBeforeMidnight, 50 * kSecond);
  // 20 s later it is past midnight: seconds-of-the-day would have jumped from 86390 to 0.
  double last = c.At_s(50 * kSecond);
  for (std::uint64_t ms = 1; ms <= 20'000; ++ms) {
    const double t = c.At_s(50 * kSecond + ms * 1'000'000ULL);
    ASSERT_NEAR(t - last, 1e-3, 1e-9) << "at " << ms << " ms";
    last = t;
  }
  EXPECT_NEAR(last, 20.0, 1e-9);
}

TEST(SessionClock, AWallClockStepAfterTheOriginArrivedChangesNothing) {
  const SessionClock c = SessionClock::FromEpoch(kBeforeMidnight, kBeforeMidnight, 50 * kSecond);
  // The wall clock is stepped an hour back; the session time reads only the steady clock.
  EXPECT_DOUBLE_EQ(c.At_s(60 * kSecond), 10.0);
  // What the server would publish again is the same origin, by the clocks of that moment.
  EXPECT_EQ(c.EpochUnixNs(kBeforeMidnight + 10 * kSecond, 60 * kSecond), kBeforeMidnight);
}

TEST(SessionClock, ADefaultClockStartsNow) {
  const SessionClock c;
  EXPECT_GE(c.Now_s(), 0.0);
  EXPECT_LT(c.Now_s(), 1.0);
  // Its origin, published and converted back on the same host, is the same clock.
  const SessionClock back = SessionClock::FromEpoch(c.EpochUnixNs());
  EXPECT_NEAR(back.Now_s(), c.Now_s(), 1e-3);
}

}  // namespace
}  // namespace handshare::common
