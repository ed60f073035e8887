#include "handshare/render/image.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <unistd.h>
#include <string>

#include "handshare/render/offscreen_renderer.hpp"

namespace handshare::render {
namespace {

std::filesystem::path TempPath(const std::string& name) {
  return std::filesystem::path(::testing::TempDir()) /
         ("handshare_render_" + std::to_string(::getpid()) + "_" + name);
}

TEST(RenderPng, RoundTripIsLossless) {
  ImageRgb8 image(37, 23);  // odd sizes: no row padding assumptions
  std::mt19937 rng(1234);
  std::uniform_int_distribution<int> byte(0, 255);
  for (auto& value : image.rgb) value = static_cast<std::uint8_t>(byte(rng));
  const auto path = TempPath("roundtrip.png");
  WritePng(path, image);
  const ImageRgb8 back = ReadPng(path);
  EXPECT_EQ(back.width_px, image.width_px);
  EXPECT_EQ(back.height_px, image.height_px);
  EXPECT_EQ(back.rgb, image.rgb);
  std::filesystem::remove(path);
}

TEST(RenderPng, RowZeroIsTheTopRowOfTheFile) {
  // A red top row and a blue bottom row must come back where they were; the PNG signature and
  // first IDAT row are checked by an independent reader where python3 exists (see below).
  ImageRgb8 image(4, 3);
  for (int col = 0; col < 4; ++col) {
    image.At(col, 0)[0] = 255;
    image.At(col, 2)[2] = 255;
  }
  const auto path = TempPath("rows.png");
  WritePng(path, image);
  const ImageRgb8 back = ReadPng(path);
  EXPECT_EQ(back.At(0, 0)[0], 255);
  EXPECT_EQ(back.At(0, 2)[2], 255);
  // The file starts with the PNG signature.
  std::ifstream file(path, std::ios::binary);
  char signature[8] = {};
  file.read(signature, 8);
  EXPECT_EQ(std::string(signature + 1, 3), "PNG");
  std::filesystem::remove(path);
}

TEST(RenderPng, RenderedImageSurvivesTheFile) {
  OffscreenRenderer renderer;
  Camera camera;
  camera.width_px = 96;
  camera.height_px = 64;
  SceneView scene;
  scene.spheres.push_back({Eigen::Vector3d::Zero(), 0.1, {1.0F, 0.5F, 0.0F}});
  scene.caption = "png";
  const ImageRgb8 image = renderer.Render(scene, camera);
  const auto path = TempPath("render.png");
  WritePng(path, image);
  EXPECT_EQ(ReadPng(path).rgb, image.rgb);
  std::filesystem::remove(path);
}

TEST(RenderPng, BadPathsGiveErrorsNamingThePath) {
  const ImageRgb8 image(2, 2);
  const std::filesystem::path missing_dir = "/nonexistent_handshare_dir/out.png";
  try {
    WritePng(missing_dir, image);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing_dir.string()), std::string::npos) << e.what();
  }
  try {
    (void)ReadPng(missing_dir);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(missing_dir.string()), std::string::npos) << e.what();
  }
  // A file that exists but is not a PNG.
  const auto not_png = TempPath("not.png");
  std::ofstream(not_png) << "this is not a png";
  try {
    (void)ReadPng(not_png);
    FAIL() << "expected std::runtime_error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(not_png.string()), std::string::npos) << e.what();
  }
  std::filesystem::remove(not_png);
}

TEST(RenderPng, InconsistentImageIsRejected) {
  ImageRgb8 image(4, 4);
  image.rgb.pop_back();
  EXPECT_THROW(WritePng(TempPath("bad.png"), image), std::invalid_argument);
  EXPECT_THROW(WritePng(TempPath("empty.png"), ImageRgb8{}), std::invalid_argument);
  EXPECT_FALSE(std::filesystem::exists(TempPath("bad.png")));
  EXPECT_THROW(ImageRgb8(-1, 3), std::invalid_argument);
}

}  // namespace
}  // namespace handshare::render
