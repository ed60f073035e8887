#include "handshare/graphics/hand_figure.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "handshare/haptic/sim_hand.hpp"
#include "handshare/hiro/hiro_device.hpp"
#include "handshare/hiro/hiro_hardware.hpp"
#include "handshare/render/offscreen_renderer.hpp"

namespace handshare::graphics {
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

TEST(HandFigure, TheUsersEyeIsBehindAndAboveTheHandAndTurnsWithIt) {
  render::Camera base;
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = Eigen::Vector3d(0.1, 0.0, 0.05);
  const render::Camera c = UserEyeCamera(X, UserEye{}, base);
  EXPECT_TRUE(c.eye_W.isApprox(Eigen::Vector3d(0.1, -0.30, 0.30)));
  EXPECT_TRUE(c.target_W.isApprox(Eigen::Vector3d(0.1, 0.08, 0.02)));
  // A hand turned 90 degrees to the left (fingers along -x): the eye is behind it, at +x.
  X.linear() = Eigen::AngleAxisd(std::numbers::pi / 2, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const render::Camera turned = UserEyeCamera(X, UserEye{}, base);
  EXPECT_TRUE(turned.eye_W.isApprox(Eigen::Vector3d(0.40, 0.0, 0.30), 1e-9));
  // A rolled hand does not roll the view.
  X.linear() = Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitY()).toRotationMatrix();
  EXPECT_TRUE(UserEyeCamera(X, UserEye{}, base).eye_W.isApprox(c.eye_W));
}

// Drawn, the hand is skin between the palm and the fingertips, which keep their colour.
TEST(HandFigure, TheDrawnHandLiesBetweenPalmAndFingertips) {
  render::OffscreenRenderer renderer;
  render::Camera camera;
  camera.eye_W = Eigen::Vector3d(0.0, 0.05, 0.5);  // from above the hand
  camera.target_W = Eigen::Vector3d(0.0, 0.05, 0.0);
  camera.up_W = Eigen::Vector3d::UnitY();
  camera.width_px = 320;
  camera.height_px = 320;
  render::SceneView scene;
  scene.grid.visible = false;
  const render::Rgb skin{0.86F, 0.70F, 0.58F};
  const HandFigure hand = FitHandToFingertips(Eigen::Isometry3d::Identity(), kOpen_H);
  AddHandFigure(hand, 0.008, skin, scene);
  for (int f = 0; f < kFingers; ++f) scene.markers.push_back(render::Sphere{kOpen_H[f], 0.008, render::Rgb{1.0F, 0.0F, 0.0F}});
  const render::ImageRgb8 image = renderer.Render(scene, camera);
  const auto is_skin = [](const std::uint8_t* p) { return p[0] > 60 && p[1] > 0.6 * p[0] && p[1] < 0.95 * p[0] && p[2] < p[1]; };
  const auto is_red = [](const std::uint8_t* p) { return p[0] > 110 && p[1] < 0.5 * p[0] && p[2] < 0.5 * p[0]; };
  int skin_px = 0, red_px = 0;
  for (int y = 0; y < image.height_px; ++y) {
    for (int x = 0; x < image.width_px; ++x) {
      skin_px += is_skin(image.At(x, y)) ? 1 : 0;
      red_px += is_red(image.At(x, y)) ? 1 : 0;
    }
  }
  EXPECT_GT(skin_px, 2000) << "palm and fingers";
  EXPECT_GT(red_px, 5 * 50) << "the five fingertips stay visible";
  // The middle finger's middle joint is skin; far to the side of the hand is not.
  const auto project = [&](const Eigen::Vector3d& p) {
    const double focal = 0.5 * camera.height_px / std::tan(0.5 * camera.fov_y_rad);
    const double depth = camera.eye_W.z() - p.z();
    return std::pair<int, int>(static_cast<int>(std::lround(0.5 * camera.width_px + focal * p.x() / depth)),
                               static_cast<int>(std::lround(0.5 * camera.height_px - focal * (p.y() - 0.05) / depth)));
  };
  const auto [mx, my] = project(hand.joints_W[2][2]);
  EXPECT_TRUE(is_skin(image.At(mx, my))) << mx << "," << my;
  const auto [sx, sy] = project(Eigen::Vector3d(0.12, 0.05, 0.0));
  EXPECT_FALSE(is_skin(image.At(sx, sy)));
}

// A fingertip behind its own hand (as the spectator, behind the users, sees them) shows
// through the hand; behind a scene object, it is hidden.
TEST(HandFigure, FingertipsShowThroughTheHandButNotThroughTheScene) {
  render::OffscreenRenderer renderer;
  render::Camera camera;
  camera.eye_W = Eigen::Vector3d(0.0, -0.5, 0.0);
  camera.target_W = Eigen::Vector3d::Zero();
  camera.width_px = 200;
  camera.height_px = 200;
  const auto centre_is_red = [&](const render::SceneView& scene) {
    const std::uint8_t* p = renderer.Render(scene, camera).At(100, 100);
    return p[0] > 110 && p[1] < 0.5 * p[0] && p[2] < 0.5 * p[0];
  };
  render::Box wall;
  wall.p_W = Eigen::Vector3d(0.0, -0.1, 0.0);  // between the eye and the fingertip
  wall.half_extents_m = Eigen::Vector3d(0.05, 0.005, 0.05);
  wall.rgb = render::Rgb{0.86F, 0.70F, 0.58F};
  render::SceneView scene;
  scene.grid.visible = false;
  scene.markers.push_back(render::Sphere{Eigen::Vector3d::Zero(), 0.01, render::Rgb{1.0F, 0.0F, 0.0F}});
  EXPECT_TRUE(centre_is_red(scene));
  scene.hand_boxes.push_back(wall);
  EXPECT_TRUE(centre_is_red(scene)) << "through the hand";
  scene.hand_boxes.clear();
  scene.boxes.push_back(wall);
  EXPECT_FALSE(centre_is_red(scene)) << "a scene object in front hides it";
}

}  // namespace
}  // namespace handshare::graphics

namespace handshare::graphics {
namespace {

// A device with fewer fingers is drawn as what the user holds, from its present fingers only:
// one point a pen rising from the fingertip's surface, two a gripper handle with a link to each.
TEST(HandFigure, AStylusIsAPenAndAPinchAGripperFromThePresentFingersOnly) {
  std::array<Eigen::Vector3d, kFingers> tips;
  for (auto& p : tips) p = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());  // absent: never read
  tips[1] = Eigen::Vector3d(0.1, 0.0, 0.02);
  render::SceneView stylus;
  AddDeviceFigure(tips, 0b00010, 0.008, render::Rgb{1.0F, 1.0F, 1.0F}, stylus);
  ASSERT_EQ(stylus.hand_boxes.size(), 1u);
  const render::Box& pen = stylus.hand_boxes[0];
  const Eigen::Vector3d axis = pen.q_WB * Eigen::Vector3d::UnitY();
  EXPECT_GT(axis.z(), 0.8);   // up
  EXPECT_LT(axis.y(), -0.3);  // towards the user
  // It starts at the fingertip sphere's surface.
  const Eigen::Vector3d bottom = pen.p_W - pen.half_extents_m.y() * axis;
  EXPECT_NEAR((bottom - tips[1]).norm(), 0.008, 1e-9);

  tips[0] = Eigen::Vector3d(0.06, 0.0, 0.02);
  render::SceneView pinch;
  AddDeviceFigure(tips, 0b00011, 0.008, render::Rgb{1.0F, 1.0F, 1.0F}, pinch);
  ASSERT_EQ(pinch.hand_boxes.size(), 3u);  // the handle and a link to each point
  for (const auto& b : pinch.hand_boxes) EXPECT_TRUE(b.p_W.allFinite());
  render::SceneView none;
  AddDeviceFigure(tips, 0, 0.008, render::Rgb{1.0F, 1.0F, 1.0F}, none);
  EXPECT_TRUE(none.hand_boxes.empty());
}

}  // namespace
}  // namespace handshare::graphics
