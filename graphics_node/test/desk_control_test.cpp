#include "handshare/graphics/desk_control.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "handshare/graphics/desk_feedback.hpp"

namespace handshare::graphics {
namespace {

render::WindowInput Focused(double x = 0.5, double y = 0.5) {
  render::WindowInput in;
  in.focused = true;
  in.cursor_inside = true;
  in.cursor_x = x;
  in.cursor_y = y;
  return in;
}

render::WindowInput Keys(const char* keys, bool shift = false) {
  render::WindowInput in = Focused();
  for (const char* k = keys; *k != 0; ++k) in.presses.push_back({*k, shift, false});
  return in;
}

TEST(DeskControl, ThePointerMovesTheHandInTheViewPlane) {
  DeskControl desk;
  desk.Apply(Focused(), 0.03);
  EXPECT_TRUE(desk.p_WH().isApprox(desk.config().home_W));
  desk.Apply(Focused(1.0, 0.0), 0.03);  // top right corner
  const Eigen::Vector3d d = desk.p_WH() - desk.config().home_W;
  EXPECT_NEAR(d.x(), desk.config().half_width_m, 1e-12);
  EXPECT_NEAR(d.y(), 0.0, 1e-12);
  EXPECT_NEAR(d.z(), desk.config().half_height_m, 1e-12);
}

TEST(DeskControl, WheelAndKeysMoveInDepthWithinBounds) {
  DeskControl desk;
  render::WindowInput in = Focused();
  in.wheel_steps = 3.0;
  desk.Apply(in, 0.03);
  EXPECT_NEAR(desk.p_WH().y() - desk.config().home_W.y(), 0.03, 1e-12);
  desk.Apply(Keys("SSSSS"), 0.03);
  EXPECT_NEAR(desk.p_WH().y() - desk.config().home_W.y(), -0.02, 1e-12);
  in.wheel_steps = 1000.0;
  desk.Apply(in, 0.03);
  EXPECT_NEAR(desk.p_WH().y() - desk.config().home_W.y(), desk.config().max_depth_m, 1e-12);
  desk.Apply(Keys("0"), 0.03);
  EXPECT_NEAR(desk.p_WH().y(), desk.config().home_W.y(), 1e-12);
}

TEST(DeskControl, KeysTurnAndTiltTheHand) {
  DeskControl desk;
  desk.Apply(Keys("AA"), 0.03);
  const Eigen::Vector3d fingers = desk.q_WH() * Eigen::Vector3d::UnitY();
  EXPECT_LT(fingers.x(), -0.1);  // turned left: the fingers point left of ahead
  EXPECT_NEAR(std::atan2(-fingers.x(), fingers.y()), 2 * desk.config().turn_step_rad, 1e-9);
  desk.Apply(Keys("0R"), 0.03);
  EXPECT_LT((desk.q_WH() * Eigen::Vector3d::UnitY()).z(), -0.05);  // tilted down
}

TEST(DeskControl, HandAndSingleFingersCloseByDegrees) {
  DeskControl desk;
  desk.Apply(Keys("CC"), 0.03);
  for (double c : desk.closure()) EXPECT_NEAR(c, 0.2, 1e-12);
  desk.Apply(Keys("22"), 0.03);
  EXPECT_NEAR(desk.closure()[1], 0.4, 1e-12);
  EXPECT_NEAR(desk.closure()[0], 0.2, 1e-12);
  desk.Apply(Keys("1", /*shift=*/true), 0.03);
  EXPECT_NEAR(desk.closure()[0], 0.1, 1e-12);
  render::WindowInput held = Focused();
  held.left_button = true;
  for (int i = 0; i < 40; ++i) desk.Apply(held, 0.05);  // 2 s held: closed
  for (double c : desk.closure()) EXPECT_EQ(c, 1.0);
  desk.Apply(Keys("O"), 0.03);
  for (double c : desk.closure()) EXPECT_EQ(c, 0.0);
}

TEST(DeskControl, WithoutFocusNothingButThePointerCounts) {
  DeskControl desk;
  render::WindowInput in = Keys("CCWW");
  in.focused = false;
  in.wheel_steps = 5;
  desk.Apply(in, 0.03);
  EXPECT_FALSE(desk.focused());
  for (double c : desk.closure()) EXPECT_EQ(c, 0.0);
  EXPECT_NEAR(desk.p_WH().y(), desk.config().home_W.y(), 1e-12);
}

TEST(DeskControl, HelpTogglesAndNamesTheKeys) {
  DeskControl desk;
  EXPECT_TRUE(desk.help_shown());
  desk.Apply(Keys("H"), 0.03);
  EXPECT_FALSE(desk.help_shown());
  for (const char* word : {"mouse", "wheel", "W/S", "A/D", "R/F", "C/V", "1-5", "Esc"}) {
    EXPECT_NE(DeskControl::HelpText().find(word), std::string::npos) << word;
  }
}

TEST(DeskFeedback, ForcesShowAsColourArrowAndHeldWeight) {
  std::array<Eigen::Vector3d, common::kFingers> tips, forces;
  for (int i = 0; i < common::kFingers; ++i) {
    tips[i] = Eigen::Vector3d(0.01 * i, 0, 0.1);
    forces[i] = Eigen::Vector3d(0, 0, -0.2);  // a held body pushes every fingertip down
  }
  forces[4].setZero();
  render::SceneView view;
  AddForceFeedback(tips, forces, 0.008, 3.5, view);
  ASSERT_EQ(view.hand_boxes.size(), 4u);  // an arrow shaft per loaded fingertip
  EXPECT_NEAR(2.0 * view.hand_boxes[0].half_extents_m.y(), 0.2 * kForceArrow_m_per_N, 1e-12);
  EXPECT_LT(view.hand_boxes[0].p_W.z(), tips[0].z());  // along the force: down
  EXPECT_NEAR(HeldWeight_N(forces), 0.8, 1e-12);
  EXPECT_NE(ForceReadout(forces).find("weight held 0.80 N"), std::string::npos) << ForceReadout(forces);
  const render::Rgb none = ForceColour(0.0, 3.5), half = ForceColour(1.75, 3.5), full = ForceColour(9.0, 3.5);
  EXPECT_EQ(none.b, 1.0F);  // white
  EXPECT_EQ(half.b, 0.0F);  // yellow
  EXPECT_EQ(half.g, 1.0F);
  EXPECT_EQ(full.g, 0.0F);  // red
}

}  // namespace
}  // namespace handshare::graphics
