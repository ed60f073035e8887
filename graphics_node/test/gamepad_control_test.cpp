#include "handshare/graphics/gamepad_control.hpp"

#include <gtest/gtest.h>
#include <limits>

namespace handshare::graphics {
namespace {

render::GamepadState Pad() {
  render::GamepadState s;
  s.connected = true;
  return s;
}

// Sticks move the hand at their speed (none inside the dead zone), within its box; triggers
// close the hand and pinch; Back brings it home.
TEST(GamepadControl, SticksMoveTheHandTriggersCloseItBackBringsItHome) {
  GamepadControl control;
  const GamepadControlConfig config;
  render::GamepadState s = Pad();
  s.left_x = 0.1;  // inside the dead zone
  s.left_y = -0.1;
  control.Apply(s, 0.05);
  EXPECT_TRUE(control.target().p_WH.isApprox(config.home_W));
  EXPECT_TRUE(control.target().focused);
  s.left_x = 1.0;   // full right
  s.left_y = 0.0;
  s.right_y = 1.0;  // full up
  for (int i = 0; i < 20; ++i) control.Apply(s, 0.05);  // 1 s
  Eigen::Vector3d moved = control.target().p_WH - config.home_W;
  EXPECT_NEAR(moved.x(), config.speed_m_per_s * 1.0, 1e-9);
  EXPECT_NEAR(moved.y(), 0.0, 1e-12);
  EXPECT_NEAR(moved.z(), config.half_extent_m.z(), 1e-12);  // 0.25 m asked, the box stops it
  // A stalled frame (2 s) moves it by at most 0.1 s worth.
  s.right_y = 0.0;
  control.Apply(s, 2.0);
  EXPECT_NEAR((control.target().p_WH - config.home_W).x(), config.speed_m_per_s * 1.1, 1e-9);
  // Right stick turns the hand about the vertical: to the right is clockwise from above.
  s = Pad();
  s.right_x = 1.0;
  control.Apply(s, 0.1);
  const Eigen::Vector3d fingers = control.target().q_WH * Eigen::Vector3d::UnitY();
  EXPECT_GT(fingers.x(), 0.1);
  // Triggers: the right closes the hand by how far it is pulled; the left pinches.
  s = Pad();
  s.right_trigger = 0.5;
  control.Apply(s, 0.01);
  for (double c : control.target().closure) EXPECT_DOUBLE_EQ(c, 0.5);
  s.right_trigger = 0.0;
  s.left_trigger = 0.8;
  control.Apply(s, 0.01);
  const auto closure = control.target().closure;
  EXPECT_DOUBLE_EQ(closure[0], 0.8);
  EXPECT_DOUBLE_EQ(closure[1], 0.8);
  for (int f = 2; f < common::kFingers; ++f) EXPECT_DOUBLE_EQ(closure[f], 0.0);
  s = Pad();
  s.back = true;
  control.Apply(s, 0.01);
  EXPECT_TRUE(control.target().p_WH.isApprox(config.home_W));
  EXPECT_TRUE(control.target().q_WH.isApprox(Eigen::Quaterniond::Identity()));
}

// A controller unplugged releases the hand; plugged back in, the hand is where it was.
TEST(GamepadControl, UnpluggedReleasesTheHand) {
  GamepadControl control;
  render::GamepadState s = Pad();
  s.left_x = 1.0;
  control.Apply(s, 0.1);
  const Eigen::Vector3d before = control.target().p_WH;
  control.Apply(render::GamepadState{}, 0.1);
  EXPECT_FALSE(control.target().focused);
  EXPECT_TRUE(control.target().p_WH.isApprox(before));
  s.left_x = 0.0;
  control.Apply(s, 0.1);
  EXPECT_TRUE(control.target().focused);
}

// Rumble: the low motor says the held weight, the high motor the largest fingertip force.
TEST(GamepadControl, RumbleSaysTheWeightHeldAndHowHardTheHandPresses) {
  GamepadControl control;
  const GamepadControlConfig config;
  GamepadRumble r = control.RumbleFor(0.0, 0.0);
  EXPECT_EQ(r.low, 0.0);
  EXPECT_EQ(r.high, 0.0);
  r = control.RumbleFor(0.324, 1.75);  // the Moon's ball, a firm press
  EXPECT_NEAR(r.low, 0.324 / config.rumble_full_weight_N, 1e-12);
  EXPECT_NEAR(r.high, 0.5, 1e-12);
  r = control.RumbleFor(50.0, std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(r.low, 1.0);
  EXPECT_EQ(r.high, 0.0);
}

}  // namespace
}  // namespace handshare::graphics
