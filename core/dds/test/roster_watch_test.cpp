#include "handshare/dds/roster_watch.hpp"

#include <gtest/gtest.h>

namespace handshare::dds {

// A member the world server has (its roster) and this node has not heard is reported once it
// has been unheard for the wait: counted from when it appeared in the roster, from when it was
// last heard, or from a rejoin. Members heard, or gone from the roster, are forgotten.
TEST(RosterWatch, AMemberTheServerHasAndThisNodeNeverHeardIsReportedAfterTheWait) {
  using namespace std::chrono_literals;
  RosterWatch watch(15s);
  const RosterWatch::Clock::time_point t0{};
  watch.OnRoster({"s/alice", "s/spectator"});
  const std::vector<std::string> spectator{"s/spectator"}, both{"s/alice", "s/spectator"};
  EXPECT_TRUE(watch.Unheard(spectator, t0).empty());
  EXPECT_TRUE(watch.Unheard(spectator, t0 + 14s).empty());
  EXPECT_EQ(watch.Unheard(spectator, t0 + 15s), std::vector<std::string>{"s/alice"});
  // Heard at last: forgotten; unheard again (a lost member): the wait starts again.
  EXPECT_TRUE(watch.Unheard(both, t0 + 16s).empty());
  EXPECT_TRUE(watch.Unheard(spectator, t0 + 17s).empty());
  EXPECT_TRUE(watch.Unheard(spectator, t0 + 31s).empty());
  EXPECT_EQ(watch.Unheard(spectator, t0 + 32s), std::vector<std::string>{"s/alice"});
  // A new participant: every wait starts again.
  watch.Restart(t0 + 32s);
  EXPECT_TRUE(watch.Unheard(spectator, t0 + 46s).empty());
  EXPECT_EQ(watch.Unheard(spectator, t0 + 47s), std::vector<std::string>{"s/alice"});
  // Gone from the roster (left the session): not waited for.
  watch.OnRoster({"s/spectator"});
  EXPECT_TRUE(watch.Unheard(spectator, t0 + 60s).empty());
  // A member joining later waits from when the roster first named it.
  watch.OnRoster({"s/bob", "s/spectator"});
  EXPECT_TRUE(watch.Unheard(spectator, t0 + 70s).empty());
  EXPECT_TRUE(watch.Unheard(spectator, t0 + 84s).empty());
  EXPECT_EQ(watch.Unheard(spectator, t0 + 85s), std::vector<std::string>{"s/bob"});
  // 0: never.
  RosterWatch never(0s);
  never.OnRoster({"s/alice"});
  EXPECT_TRUE(never.Unheard({}, t0).empty());
  EXPECT_TRUE(never.Unheard({}, t0 + 1000s).empty());
}

}  // namespace handshare::dds
