#include "handshare/render/window_renderer.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "handshare/render/offscreen_renderer.hpp"
#include "test_oracle.hpp"

namespace handshare::render {
namespace {

// Run under a virtual display (ctest uses xvfb-run); skips where no display is reachable.
class RenderWindow : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!WindowRenderer::DisplayAvailable()) GTEST_SKIP() << "no display";
  }
};

SceneView RedSphereScene(const Camera& camera) {
  SceneView scene;
  scene.spheres.push_back({camera.target_W + Eigen::Vector3d(0.1, 0.0, 0.05), 0.04, {1.0F, 0.0F, 0.0F}});
  scene.caption = "window";
  return scene;
}

TEST_F(RenderWindow, ShowsTheSamePictureAsTheOffscreenRenderer) {
  WindowRenderer::Options options;
  options.width_px = 200;
  options.height_px = 150;
  options.visible = true;
  WindowRenderer window(options);
  ASSERT_GT(window.framebuffer_width_px(), 0);
  Camera camera;
  camera.width_px = window.framebuffer_width_px();
  camera.height_px = window.framebuffer_height_px();
  const SceneView scene = RedSphereScene(camera);

  OffscreenRenderer offscreen;
  // Interleave both context kinds on one thread: each must still draw into its own target.
  for (int round = 0; round < 2; ++round) {
    const ImageRgb8 reference = offscreen.Render(scene, camera);
    window.Render(scene, camera);  // plain path first: it must leave the context usable
    const ImageRgb8 shown = window.RenderAndCapture(scene, camera);
    ASSERT_EQ(shown.width_px, reference.width_px);
    ASSERT_EQ(shown.height_px, reference.height_px);
    const test::PixelPoint centre = test::OracleProject(camera, scene.spheres[0].p_W);
    const std::uint8_t* px = shown.At(static_cast<int>(centre.col), static_cast<int>(centre.row));
    EXPECT_GT(px[0], 150);
    EXPECT_LT(px[1], 80);
    // Same driver (llvmpipe) either way: allow a little rasterization difference at edges.
    int differing = 0;
    for (std::size_t i = 0; i < shown.rgb.size(); ++i) {
      if (std::abs(int{shown.rgb[i]} - int{reference.rgb[i]}) > 8) ++differing;
    }
    EXPECT_LT(differing, static_cast<int>(shown.rgb.size() / 100)) << "round " << round;
  }
  EXPECT_FALSE(window.ShouldClose());
}

TEST(RenderWindowNoDisplay, ConstructionFailsWithAReasonWhenThereIsNoDisplay) {
  if (WindowRenderer::DisplayAvailable()) GTEST_SKIP() << "a display is available";
  try {
    WindowRenderer window(WindowRenderer::Options{});
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("GLFW"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace handshare::render
