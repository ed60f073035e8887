#include "handshare/figure/hand_figure.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>

#include "handshare/haptic/sim_hand.hpp"
#include "handshare/hiro/hiro_device.hpp"
#include "handshare/hiro/hiro_hardware.hpp"
#include "handshare/hiro/hiro_model.hpp"

namespace handshare::figure {
namespace {

// The simulated hand's fingertips, open and closed (core/device/src/sim_hand.cpp, GripOffsets).
const std::array<Eigen::Vector3d, kFingers> kOpen_H = {
    Eigen::Vector3d(-0.060, 0.040, -0.010), Eigen::Vector3d(-0.036, 0.100, 0.000), Eigen::Vector3d(-0.012, 0.105, 0.000),
    Eigen::Vector3d(0.012, 0.100, 0.000), Eigen::Vector3d(0.036, 0.090, 0.000)};
const std::array<Eigen::Vector3d, kFingers> kClosed_H = {
    Eigen::Vector3d(-0.025, 0.060, -0.030), Eigen::Vector3d(0.000, 0.075, -0.020), Eigen::Vector3d(0.012, 0.070, -0.025),
    Eigen::Vector3d(0.020, 0.062, -0.028), Eigen::Vector3d(0.024, 0.055, -0.030)};

Eigen::Isometry3d SomePose() {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.2, -0.3, 1.0).normalized()).toRotationMatrix();
  X.translation() = Eigen::Vector3d(0.05, -0.02, 0.12);
  return X;
}

// Every finger's links keep their lengths, start at its knuckle and end at its fingertip; the
// finger bends towards the palm (its joints lie on the back of the hand's side of the chord).
void ExpectAFittedHand(const HandFigure& hand, const Eigen::Isometry3d& X_WH, const std::array<Eigen::Vector3d, kFingers>& tips_W) {
  const Eigen::Vector3d palm_W = -(X_WH.linear() * Eigen::Vector3d::UnitZ());
  for (int f = 0; f < kFingers; ++f) {
    const auto& j = hand.joints_W[f];
    EXPECT_LT((j[0] - X_WH * HandKnuckles_H()[f]).norm(), 1e-12) << f;
    EXPECT_LT((j[3] - tips_W[f]).norm(), 1e-12) << f;
    if (hand.stretched[f]) continue;
    for (int k = 0; k < 3; ++k) EXPECT_NEAR((j[k + 1] - j[k]).norm(), HandLinkLengths()[f][k], 1e-9) << f << "/" << k;
    const Eigen::Vector3d u = (j[3] - j[0]).normalized();
    for (int k = 1; k < 3; ++k) {
      const Eigen::Vector3d off = (j[k] - j[0]) - (j[k] - j[0]).dot(u) * u;
      EXPECT_LE(off.dot(palm_W), 1e-9) << f << "/" << k << ": a joint on the palm's side";
    }
  }
}

TEST(HandFigure, FitsTheSimulatedHandOpenAndClosedAtAnyPose) {
  for (const Eigen::Isometry3d& X_WH : {Eigen::Isometry3d(Eigen::Isometry3d::Identity()), SomePose()}) {
    for (const auto* shape : {&kOpen_H, &kClosed_H}) {
      std::array<Eigen::Vector3d, kFingers> tips_W;
      for (int f = 0; f < kFingers; ++f) tips_W[f] = X_WH * (*shape)[f];
      const HandFigure hand = FitHandToFingertips(X_WH, tips_W);
      for (int f = 0; f < kFingers; ++f) EXPECT_FALSE(hand.stretched[f]) << f << ": the sim hand is within reach";
      ExpectAFittedHand(hand, X_WH, tips_W);
    }
  }
}

TEST(HandFigure, RandomFingertipsAreReachedOrTheFingerStretches) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> box(-0.15, 0.15);
  int stretched = 0;
  for (int trial = 0; trial < 500; ++trial) {
    std::array<Eigen::Vector3d, kFingers> tips;
    for (auto& t : tips) t = Eigen::Vector3d(box(rng), box(rng) + 0.05, box(rng));
    const HandFigure hand = FitHandToFingertips(SomePose(), tips);
    ExpectAFittedHand(hand, SomePose(), tips);
    for (int f = 0; f < kFingers; ++f) {
      const double length = HandLinkLengths()[f][0] + HandLinkLengths()[f][1] + HandLinkLengths()[f][2];
      EXPECT_EQ(hand.stretched[f], (tips[f] - hand.joints_W[f][0]).norm() > length * (1 + 1e-9));
      stretched += hand.stretched[f] ? 1 : 0;
    }
  }
  EXPECT_GT(stretched, 100);  // both branches were exercised
}

TEST(HandFigure, BadFingertipsGiveAStraightHandNotNaN) {
  std::array<Eigen::Vector3d, kFingers> tips;
  tips.fill(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  const HandFigure hand = FitHandToFingertips(Eigen::Isometry3d::Identity(), tips);
  for (const auto& finger : hand.joints_W) {
    for (const auto& j : finger) EXPECT_TRUE(j.allFinite());
  }
}

// The HIRO II's hand, drawn from the joint angles its device state carries, ends at the
// fingertips the same state reports (the device's own kinematics, run by its driver on its
// simulated plant, as an independent path), with the model's link lengths.
TEST(HandFigure, TheHiroHandFromItsJointAnglesReachesTheReportedFingertips) {
  const std::string config = std::string(HANDSHARE_SOURCE_ASSETS) + "/devices/hiro2.json";
  hiro::HiroSimOptions sim;
  sim.script = haptic::HandScript::Parse("start 0 0 0\nmove 0.4 0.03 0.02 0.01 grip 1\nmove 0.4 -0.02 0.0 0.03 grip 0\n", "t");
  auto device = hiro::MakeSimulatedHiroDevice(config, sim);
  const hiro::HiroModel& model = device->model();
  haptic::DeviceReading r;
  double worst_m = 0.0;
  for (int n = 1; n <= 800; ++n) {
    device->Read(n * 1e-3, r);
    ASSERT_TRUE(r.valid);
    device->Command({});
    if (n % 50 != 0) continue;
    Eigen::Isometry3d X_WH = Eigen::Isometry3d::Identity();
    X_WH.linear() = Eigen::Quaterniond(r.q_WH_wxyz[0], r.q_WH_wxyz[1], r.q_WH_wxyz[2], r.q_WH_wxyz[3]).toRotationMatrix();
    X_WH.translation() = r.p_WH;
    const HandFigure hand = HiroHandFigure(model, X_WH, r.q_hand_rad);
    for (int f = 0; f < kFingers; ++f) {
      worst_m = std::max(worst_m, (hand.joints_W[f][3] - r.p_WE[f]).norm());
      for (int k = 0; k < 2; ++k) {
        EXPECT_NEAR((hand.joints_W[f][k + 1] - hand.joints_W[f][k]).norm(), model.finger[f].link_m[k], 1e-9) << f;
      }
    }
  }
  EXPECT_LT(worst_m, 1e-9) << "the drawn fingertips are where the device says they are";
}

// A device with fewer fingers is drawn as what the user holds, from its present fingers only:
// one point a pen rising from the fingertip's surface, two a gripper handle with a link to each.
TEST(HandFigure, AStylusIsAPenAndAPinchAGripperFromThePresentFingersOnly) {
  std::array<Eigen::Vector3d, kFingers> tips;
  for (auto& p : tips) p = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());  // absent: never read
  tips[1] = Eigen::Vector3d(0.1, 0.0, 0.02);
  HandParts stylus;
  AddDeviceFigure(tips, 0b00010, 0.008, stylus);
  ASSERT_EQ(stylus.boxes.size(), 1u);
  const Box& pen = stylus.boxes[0];
  const Eigen::Vector3d axis = pen.q_WB * Eigen::Vector3d::UnitY();
  EXPECT_GT(axis.z(), 0.8);   // up
  EXPECT_LT(axis.y(), -0.3);  // towards the user
  // It starts at the fingertip sphere's surface.
  const Eigen::Vector3d bottom = pen.p_W - pen.half_extents_m.y() * axis;
  EXPECT_NEAR((bottom - tips[1]).norm(), 0.008, 1e-9);

  tips[0] = Eigen::Vector3d(0.06, 0.0, 0.02);
  HandParts pinch;
  AddDeviceFigure(tips, 0b00011, 0.008, pinch);
  ASSERT_EQ(pinch.boxes.size(), 3u);  // the handle and a link to each point
  for (const auto& b : pinch.boxes) EXPECT_TRUE(b.p_W.allFinite());
  HandParts none;
  AddDeviceFigure(tips, 0, 0.008, none);
  EXPECT_TRUE(none.boxes.empty());
}


// The rule the screens and the web console's view both draw by: five fingers fitted (skin), a
// HIRO II's from its joint angles with its model (metal), fewer fingers a pen or a gripper.
TEST(HandFigure, TheDrawnHandFollowsTheDevice) {
  DeviceHand hand;
  hand.p_WH_m = {0.05, -0.02, 0.12};
  const Eigen::Isometry3d X_WH = HandBasePose(hand.p_WH_m, hand.q_WH_wxyz);
  for (int f = 0; f < kFingers; ++f) hand.p_WE[f] = X_WH * kOpen_H[f];
  hand.fingertip_radius_m = 0.008;
  const HandParts fitted = DrawnHand(hand, nullptr);
  EXPECT_EQ(fitted.rgb, kSkinRgb);
  ASSERT_EQ(fitted.boxes.size(), 1u + 3u * kFingers);  // the palm, three links a finger
  ASSERT_EQ(fitted.spheres.size(), 3u * kFingers);     // three joints a finger (the fingertips are the caller's)
  const HandFigure fit = FitHandToFingertips(X_WH, hand.p_WE);
  EXPECT_LT((fitted.boxes[0].p_W - X_WH * fit.palm_center_H).norm(), 1e-12);
  for (int f = 0; f < kFingers; ++f) {
    for (int k = 0; k < 3; ++k) EXPECT_LT((fitted.spheres[3 * f + k].p_W - fit.joints_W[f][k]).norm(), 1e-12) << f;
    // The last link ends at the fingertip sphere's surface.
    const Box& last = fitted.boxes[1 + 3 * f + 2];
    const Eigen::Vector3d end = last.p_W + last.half_extents_m.y() * (last.q_WB * Eigen::Vector3d::UnitY());
    EXPECT_NEAR((end - hand.p_WE[f]).norm(), 0.008, 1e-9) << f;
  }
  // A HIRO II user's without the model is fitted too; with it, drawn from the joint angles.
  hand.hiro = true;
  EXPECT_EQ(DrawnHand(hand, nullptr).rgb, kSkinRgb);
  const hiro::HiroModel model = hiro::HiroModel::Load(std::string(HANDSHARE_SOURCE_ASSETS) + "/devices/hiro2.json");
  const HandParts metal = DrawnHand(hand, &model);
  EXPECT_EQ(metal.rgb, kHiroRgb);
  const HandFigure robot = HiroHandFigure(model, X_WH, hand.q_hand_rad);
  ASSERT_EQ(metal.spheres.size(), 3u * kFingers);
  EXPECT_LT((metal.spheres[3].p_W - robot.joints_W[1][0]).norm(), 1e-12);
  // A stylus (the index only): one pen.
  hand.absent_fingers = 0b11101;
  const HandParts pen = DrawnHand(hand, &model);
  EXPECT_EQ(pen.rgb, kSkinRgb);
  EXPECT_EQ(pen.boxes.size(), 1u);
  EXPECT_TRUE(pen.spheres.empty());
}

// An unusable quaternion gives the identity rotation at the hand base; a usable one is normalized.
TEST(HandFigure, TheHandBasePoseOfADeviceState) {
  const Eigen::Isometry3d bad = HandBasePose({0.1, 0.2, 0.3}, {0.0, 0.0, 0.0, 0.0});
  EXPECT_TRUE(bad.linear().isIdentity());
  EXPECT_TRUE(bad.translation().isApprox(Eigen::Vector3d(0.1, 0.2, 0.3)));
  const Eigen::Isometry3d turned = HandBasePose({0.0, 0.0, 0.0}, {2.0, 0.0, 0.0, 2.0});
  EXPECT_TRUE((turned.linear() * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY()));
}

}  // namespace
}  // namespace handshare::figure
