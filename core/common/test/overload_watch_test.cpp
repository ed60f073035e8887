#include "handshare/common/overload_watch.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <vector>

namespace handshare::common {
namespace {

// Ticks every period_s from t_s for duration_s, each interval asked to be asked_s long (0: the
// watch's rate); returns the lines the watch said, and moves t_s.
std::vector<std::string> TickFor(OverloadWatch& watch, double& t_s, double period_s, double duration_s,
                                 double asked_s = 0.0) {
  std::vector<std::string> said;
  const double end_s = t_s + duration_s;
  for (; t_s < end_s - 1e-12; t_s += period_s) {
    std::string line = watch.Tick(static_cast<std::uint64_t>(t_s * 1e9) + 1'000'000'000ULL, asked_s);
    if (!line.empty()) said.push_back(line);
  }
  return said;
}

TEST(OverloadWatch, AThreadThatKeepsItsRateSaysNothing) {
  OverloadWatch watch("the bridge", {});
  double t_s = 0.0;
  EXPECT_TRUE(TickFor(watch, t_s, 0.010, 10.0).empty());
  EXPECT_TRUE(TickFor(watch, t_s, 0.018, 10.0).empty()) << "55 Hz is above the 50 Hz bound";
  EXPECT_FALSE(watch.overloaded());
  EXPECT_EQ(watch.Summary(), "no overload");
}

// The bridge with nothing to carry asks for a tick every 50 ms (HapticBridge::kIdleTick): at that
// period it is on time, not a bridge at 20 Hz of 100; starved to a quarter of what it asks, or
// one interval 100 ms over it, it is overloaded as a busy bridge would be.
TEST(OverloadWatch, AThreadAskingForLongerIntervalsIsJudgedByWhatItAsked) {
  OverloadWatch watch("the bridge", {});
  double t_s = 0.0;
  EXPECT_TRUE(TickFor(watch, t_s, 0.050, 10.0, 0.050).empty()) << "idle ticks on time";
  EXPECT_TRUE(TickFor(watch, t_s, 0.010, 3.0).empty()) << "busy again at 100 Hz";
  EXPECT_FALSE(watch.overloaded());
  const std::vector<std::string> starved = TickFor(watch, t_s, 0.200, 4.0, 0.050);
  ASSERT_EQ(starved.size(), 1U);
  EXPECT_NE(starved[0].find("the machine is overloaded: the bridge ran at"), std::string::npos) << starved[0];
  EXPECT_NE(starved[0].find("(longest interval 200 ms)"), std::string::npos) << starved[0];
  // Starved evenly, without a late interval: a quarter of the idle ticks asked for.
  OverloadWatch slow("the bridge", {.rate_Hz = 100.0, .min_rate_Hz = 50.0, .max_interval_s = 1.0, .window_s = 2.0});
  double t1 = 0.0;
  const std::vector<std::string> quarter = TickFor(slow, t1, 0.200, 4.0, 0.050);
  ASSERT_EQ(quarter.size(), 1U);
  EXPECT_NE(quarter[0].find("ran at 25.0 Hz of 100"), std::string::npos) << quarter[0];
  const std::vector<std::string> back = TickFor(watch, t_s, 0.050, 5.0, 0.050);
  ASSERT_EQ(back.size(), 1U);
  EXPECT_NE(back[0].find("keeps its rate again (100.0 Hz of 100"), std::string::npos) << back[0];
  // One idle interval 60 ms late (110 ms for 50): under the 90 ms a 100 Hz tick may run over.
  double t2 = 0.0;
  OverloadWatch once("the bridge", {});
  TickFor(once, t2, 0.050, 1.0, 0.050);
  EXPECT_EQ(once.Tick(static_cast<std::uint64_t>((t2 + 0.060) * 1e9) + 1'000'000'000ULL, 0.050), "");
  EXPECT_FALSE(once.overloaded());
}

TEST(OverloadWatch, AStarvedThreadSaysSoOnceAndAgainWhenItRecovers) {
  OverloadWatch watch("the bridge", {});
  double t_s = 0.0;
  ASSERT_TRUE(TickFor(watch, t_s, 0.010, 3.0).empty());
  // 20 Hz: every interval 50 ms (under the 100 ms bound), the rate under 50 Hz.
  const std::vector<std::string> starved = TickFor(watch, t_s, 0.050, 6.0);
  ASSERT_EQ(starved.size(), 1U) << "one line for the whole overload, not one per window";
  EXPECT_NE(starved[0].find("the machine is overloaded: the bridge ran at"), std::string::npos) << starved[0];
  EXPECT_TRUE(watch.overloaded());
  const std::vector<std::string> well = TickFor(watch, t_s, 0.010, 5.0);
  ASSERT_EQ(well.size(), 1U);
  EXPECT_NE(well[0].find("the bridge keeps its rate again ("), std::string::npos) << well[0];
  EXPECT_FALSE(watch.overloaded());
  EXPECT_EQ(watch.episodes(), 1);
  // Overloaded from the end of the first slow window until the first whole good window closed.
  EXPECT_GT(watch.overloaded_s(), 3.5);
  EXPECT_LT(watch.overloaded_s(), 9.0);
  EXPECT_NE(watch.Summary().find("overloaded 1 time(s)"), std::string::npos);
}

TEST(OverloadWatch, OneLongStallIsAnOverloadAtOnce) {
  OverloadWatch watch("the tick", {60.0, 30.0, 0.1, 2.0});
  double t_s = 0.0;
  ASSERT_TRUE(TickFor(watch, t_s, 1.0 / 60.0, 0.5).empty());
  t_s += 0.3;  // the thread got no CPU for 300 ms
  const std::string line = watch.Tick(static_cast<std::uint64_t>(t_s * 1e9) + 1'000'000'000ULL);
  EXPECT_NE(line.find("the machine is overloaded: the tick ran at"), std::string::npos) << line;
  EXPECT_NE(line.find("longest interval 31"), std::string::npos) << line;
  const std::vector<std::string> after = TickFor(watch, t_s, 1.0 / 60.0, 3.0);
  ASSERT_EQ(after.size(), 1U);
  EXPECT_NE(after[0].find("the tick keeps its rate again"), std::string::npos) << after[0];
}

// Every dinosaur session in CI began with "the machine is overloaded: the bridge ran at 1.6 Hz of
// 100 ... (longest interval 1250 ms)": the bridge had built the world's models for 1.1 s. Work
// of the thread's own, marked with Restart, is no overload; a stall after it still is.
TEST(OverloadWatch, TheThreadsOwnWorkMarkedWithRestartIsNoOverload) {
  OverloadWatch watch("the bridge", {});
  double t_s = 0.0;
  ASSERT_TRUE(TickFor(watch, t_s, 0.010, 0.5).empty());
  t_s += 1.25;  // building a world's models
  watch.Restart(static_cast<std::uint64_t>(t_s * 1e9) + 1'000'000'000ULL);
  EXPECT_TRUE(TickFor(watch, t_s, 0.010, 5.0).empty());
  EXPECT_EQ(watch.Summary(), "no overload");
  t_s += 0.3;  // and then a stall that is not its own
  const std::string line = watch.Tick(static_cast<std::uint64_t>(t_s * 1e9) + 1'000'000'000ULL);
  EXPECT_NE(line.find("the machine is overloaded"), std::string::npos) << line;
}

}  // namespace
}  // namespace handshare::common
