// A loop's statistics other than the haptic loop's: what the operator's page and the session
// log show of a screen (a graphics node's frames) or a guide.
#include "handshare/dds/pass_statistics.hpp"

#include <gtest/gtest.h>

namespace handshare::dds {
namespace {

using namespace std::chrono_literals;
using Clock = PassStatistics::Clock;

// 30 fps for 1 s: frames on time, one 10 ms late, one 40 ms late (a frame period and more:
// missed), each drawn in 5 ms; then a quiet second.
TEST(PassStatistics, RateJitterDrawTimeAndMissedFramesPerPeriod) {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / 30));
  const Clock::time_point t0{};
  PassStatistics stats(period, t0);
  for (int i = 0; i < 30; ++i) {
    const auto due = t0 + i * period;
    const auto late = i == 10 ? 10ms : i == 20 ? 40ms : 0ms;
    stats.Record(due, due + late, due + late + 5ms);
  }
  msg::LoopStatistics out;
  stats.Fill(out, t0 + 1s);
  EXPECT_DOUBLE_EQ(out.rate_Hz(), 30.0);
  EXPECT_EQ(out.steps(), 30u);
  EXPECT_EQ(out.overruns(), 1u);
  EXPECT_EQ(out.jitter_p50_us(), 1.0);  // on time: the histogram's first bin's upper edge
  EXPECT_NEAR(out.jitter_max_us(), 40000.0, 1.0);
  EXPECT_NEAR(out.jitter_p99_us(), 40000.0, 400.0);  // 1 % bins above 1 ms
  EXPECT_NEAR(out.step_p99_us(), 5000.0, 50.0);
  // A period without frames: no rate, no times, the counts stay.
  stats.Fill(out, t0 + 2s);
  EXPECT_EQ(out.rate_Hz(), 0.0);
  EXPECT_EQ(out.jitter_max_us(), 0.0);
  EXPECT_EQ(out.steps(), 30u);
  EXPECT_EQ(out.overruns(), 1u);
  // A frame a new hand state brings forward (begun before the clock's due time) is not late.
  stats.Record(t0 + 2s + period, t0 + 2s + 1ms, t0 + 2s + 2ms);
  stats.Fill(out, t0 + 3s);
  EXPECT_EQ(out.jitter_max_us(), 0.0);
  EXPECT_EQ(out.overruns(), 1u);
}

}  // namespace
}  // namespace handshare::dds
