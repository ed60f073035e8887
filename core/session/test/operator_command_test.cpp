#include <gtest/gtest.h>

#include "handshare/session/operator_command.hpp"

namespace handshare::session {
namespace {

using controls::OperatorAction;
using controls::OperatorCommand;

// Each action goes out as its kind with only its own name set, and comes back as it went.
TEST(OperatorCommand, EachActionGoesBothWaysWithOnlyItsName) {
  const OperatorCommand go{OperatorAction::kGoToWorld, "dinosaur", "alice"};
  msg::OperatorCommand m = ToMessage(go, "museum", "web-console", 7);
  EXPECT_EQ(m.kind(), msg::OPERATOR_GO_TO_WORLD);
  EXPECT_EQ(m.session().to_string(), "museum");
  EXPECT_EQ(m.user().to_string(), "web-console");
  EXPECT_EQ(m.world().to_string(), "dinosaur");
  EXPECT_EQ(m.visitor().to_string(), "");  // not a go-to-world's field
  EXPECT_EQ(m.stamp_ns(), 7u);
  auto back = FromMessage(m);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->action, OperatorAction::kGoToWorld);
  EXPECT_EQ(back->world, "dinosaur");

  m = ToMessage({OperatorAction::kEndTurn, "dinosaur", "alice"}, "museum", "web-console", 8);
  EXPECT_EQ(m.kind(), msg::OPERATOR_END_TURN);
  EXPECT_EQ(m.world().to_string(), "");
  back = FromMessage(m);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->action, OperatorAction::kEndTurn);
  EXPECT_EQ(back->visitor, "alice");

  m = ToMessage({OperatorAction::kRestartTour, "", ""}, "museum", "web-console", 9);
  EXPECT_EQ(m.kind(), msg::OPERATOR_RESTART_TOUR);
  back = FromMessage(m);
  ASSERT_TRUE(back);
  EXPECT_EQ(back->action, OperatorAction::kRestartTour);
  EXPECT_STREQ(ToString(back->action), "restart_tour");

  m.kind(static_cast<msg::OperatorCommandKind>(9));
  EXPECT_FALSE(FromMessage(m));
}

}  // namespace
}  // namespace handshare::session
