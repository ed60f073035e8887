// The rule every roster watcher rejoins by: a member of the world server's roster unheard for
// the wait makes one rejoin, the wait starts again with the new participant, and the rejoins are
// capped.
#include "handshare/dds/roster_rejoin.hpp"

#include <gtest/gtest.h>

#include <chrono>

namespace handshare::dds {
namespace {

using std::chrono::milliseconds;

TEST(RosterRejoin, AMemberUnheardForTheWaitMakesOneRejoinAndTheRejoinsAreCapped) {
  RosterRejoin rule(std::chrono::duration<double>(2.5), "museum");
  const auto t0 = RosterRejoin::Clock::now();
  rule.OnRoster({"museum/world_server", "museum/alice", "museum/bob"});
  const std::vector<std::string> heard = {"museum/world_server", "museum/alice"};
  EXPECT_EQ(rule.Due(heard, t0), "") << "the wait starts now";
  EXPECT_EQ(rule.Due(heard, t0 + milliseconds(2400)), "");
  EXPECT_EQ(rule.Due(heard, t0 + milliseconds(2500)),
            "the world server has museum/bob, not heard here 2.5 s after joining: leaving and joining again with a "
            "new participant (rejoin 1)");
  EXPECT_EQ(rule.rejoins(), 1);
  // The new participant's wait starts again; bob heard now: nothing.
  rule.Restart(t0 + milliseconds(2600));
  EXPECT_EQ(rule.Due(heard, t0 + milliseconds(4000)), "");
  EXPECT_EQ(rule.Due({"museum/world_server", "museum/alice", "museum/bob"}, t0 + milliseconds(6000)), "");
  // Bob never heard again: one rejoin per wait, five in all.
  auto t = t0 + milliseconds(6000);
  for (int k = 2; k <= RosterRejoin::kMaxRejoins; ++k) {
    (void)rule.Due(heard, t);
    t += milliseconds(2500);
    EXPECT_NE(rule.Due(heard, t).find("(rejoin " + std::to_string(k) + ")"), std::string::npos) << k;
    rule.Restart(t);
  }
  t += milliseconds(10000);
  EXPECT_EQ(rule.Due(heard, t), "") << "capped";
  EXPECT_EQ(rule.rejoins(), RosterRejoin::kMaxRejoins);
}

TEST(RosterRejoin, NoWaitNeverRejoins) {
  RosterRejoin rule(std::chrono::duration<double>(0.0), "museum");
  const auto t0 = RosterRejoin::Clock::now();
  rule.OnRoster({"museum/bob"});
  EXPECT_EQ(rule.Due({}, t0), "");
  EXPECT_EQ(rule.Due({}, t0 + std::chrono::hours(1)), "");
}

}  // namespace
}  // namespace handshare::dds
