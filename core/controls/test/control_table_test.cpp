// The paper's Table 4 rule that the session report and the web console's live table share.
#include <gtest/gtest.h>

#include <cmath>

#include "handshare/controls/control_table.hpp"

namespace handshare::controls {
namespace {

TEST(Summarize, SampleMeanAndSdWithNMinusOne) {
  const Summary s = Summarize({1.0, 2.0, 4.0});
  EXPECT_EQ(s.n, 3u);
  EXPECT_DOUBLE_EQ(s.mean, 7.0 / 3.0);
  // sum of squared deviations: (4/3)^2 + (1/3)^2 + (5/3)^2 = 42/9, over n - 1 = 2
  EXPECT_DOUBLE_EQ(s.sd, std::sqrt(42.0 / 9.0 / 2.0));
  EXPECT_EQ(Summarize({}).n, 0u);
  EXPECT_EQ(Summarize({5.0}).sd, 0.0);
}

// Hits carry their errors (a non-finite one is left out), a release is neither, a miss counts
// for its user; misses per user are over everyone who tried, 0 for a user who never missed.
TEST(EventTally, HitsMissesAndMissesPerUserOverEveryoneWhoTried) {
  EventTally t;
  t.Add(EventKind::kPressed, "alice", 0.002);
  t.Add(EventKind::kReleased, "alice", std::nullopt);
  t.Add(EventKind::kMissed, "bob", 0.03);
  t.Add(EventKind::kMissed, "bob", std::nullopt);
  t.Add(EventKind::kOpened, "carol", NAN);
  EXPECT_EQ(t.hits(), 2u);
  EXPECT_EQ(t.misses(), 2u);
  EXPECT_EQ(t.released(), 1u);
  EXPECT_EQ(t.error_m().n, 1u);
  EXPECT_DOUBLE_EQ(t.error_m().mean, 0.002);
  const Summary per_user = t.misses_per_user();  // alice 0, bob 2, carol 0
  EXPECT_EQ(per_user.n, 3u);
  EXPECT_DOUBLE_EQ(per_user.mean, 2.0 / 3.0);
}

TEST(KindTable, RowsPerKindInThePapersOrderWithUnknownLast) {
  KindTable table;
  EXPECT_TRUE(table.empty());
  table.Add("lever_planet", scene::ControlType::kLever, EventKind::kMoved, "alice", 0.01);
  table.Add("button_dino", scene::ControlType::kButton, EventKind::kPressed, "alice", 0.001);
  table.Add("button_solar", scene::ControlType::kButton, EventKind::kMissed, "bob", std::nullopt);
  table.Add("old_knob", std::nullopt, EventKind::kPressed, "bob", std::nullopt);
  table.Add("arrow_next", scene::ControlType::kArrow, EventKind::kPressed, "bob", 0.004);
  const auto rows = table.Rows();
  ASSERT_EQ(rows.size(), 4u);
  EXPECT_EQ(rows[0].kind, "arrow");
  EXPECT_EQ(rows[1].kind, "button");
  EXPECT_EQ(rows[1].controls, 2u);
  EXPECT_EQ(rows[1].tally.hits(), 1u);
  EXPECT_EQ(rows[1].tally.misses(), 1u);
  EXPECT_EQ(rows[2].kind, "lever");
  EXPECT_EQ(rows[3].kind, KindTable::kUnknown);
}

}  // namespace
}  // namespace handshare::controls
