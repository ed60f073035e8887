#include "handshare/session/control_events.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace handshare::session {
namespace {

using controls::EventKind;

constexpr EventKind kEveryKind[] = {EventKind::kPressed, EventKind::kReleased, EventKind::kMoved,
                                    EventKind::kPageTurned, EventKind::kMissed, EventKind::kOpened,
                                    EventKind::kMoving};

TEST(ControlEventKinds, EveryKindCrossesTheBoundaryAndComesBackItself) {
  for (EventKind k : kEveryKind) {
    const auto back = FromMessage(ToMessage(k));
    ASSERT_TRUE(back.has_value()) << controls::ToString(k);
    EXPECT_EQ(*back, k) << controls::ToString(k);
  }
  // An opened book is its own kind on the wire, not a press.
  EXPECT_EQ(ToMessage(EventKind::kOpened), msg::CONTROL_OPENED);
  EXPECT_NE(ToMessage(EventKind::kOpened), ToMessage(EventKind::kPressed));
}

TEST(ControlEventKinds, AValueOutsideTheEnumerationIsRejected) {
  EXPECT_FALSE(FromMessage(static_cast<msg::ControlEventKind>(7)).has_value());
  EXPECT_FALSE(FromMessage(static_cast<msg::ControlEventKind>(-1)).has_value());
}

TEST(ControlEventKinds, TheSampleCarriesEveryField) {
  controls::ControlEvent e;
  const std::string id = "book_dino";
  std::copy(id.begin(), id.end(), e.control_id.begin());
  e.kind = EventKind::kPageTurned;
  e.value = 2.0;
  e.index = 2;
  e.error_m = 0.004;
  const msg::ControlEvent m = ToMessage(e, "museum", "alice", 1234u);
  EXPECT_EQ(m.session().to_string(), "museum");
  EXPECT_EQ(m.user().to_string(), "alice");
  EXPECT_EQ(m.control_id().to_string(), "book_dino");
  EXPECT_EQ(m.kind(), msg::CONTROL_PAGE_TURNED);
  EXPECT_EQ(m.value(), 2.0);
  EXPECT_EQ(m.index(), 2);
  EXPECT_EQ(m.error_m(), 0.004);
  EXPECT_EQ(m.stamp_ns(), 1234u);
}

}  // namespace
}  // namespace handshare::session
