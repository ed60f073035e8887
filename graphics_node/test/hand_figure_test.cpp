#include "handshare/graphics/hand_figure.hpp"

#include <gtest/gtest.h>

#include <numbers>

#include "handshare/render/offscreen_renderer.hpp"

namespace handshare::graphics {
namespace {

// The simulated hand's fingertips, open and closed (core/device/src/sim_hand.cpp, GripOffsets).
const std::array<Eigen::Vector3d, kFingers> kOpen_H = {
    Eigen::Vector3d(-0.060, 0.040, -0.010), Eigen::Vector3d(-0.036, 0.100, 0.000), Eigen::Vector3d(-0.012, 0.105, 0.000),
    Eigen::Vector3d(0.012, 0.100, 0.000), Eigen::Vector3d(0.036, 0.090, 0.000)};
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
  const figure::HandFigure hand = figure::FitHandToFingertips(Eigen::Isometry3d::Identity(), kOpen_H);
  figure::HandParts parts;
  parts.rgb = figure::kSkinRgb;
  figure::AddHandFigure(hand, 0.008, parts);
  AddHandParts(parts, scene);
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
