#include "handshare/render/offscreen_renderer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>

#include "test_oracle.hpp"

namespace handshare::render {
namespace {

using test::OracleProject;
using test::PixelPoint;

constexpr Rgb kRed{1.0F, 0.0F, 0.0F};
constexpr Rgb kGreen{0.0F, 1.0F, 0.0F};
constexpr Rgb kBlue{0.0F, 0.0F, 1.0F};
constexpr Rgb kYellow{1.0F, 1.0F, 0.0F};
constexpr Rgb kCyan{0.0F, 1.0F, 1.0F};
constexpr Rgb kWhite{1.0F, 1.0F, 1.0F};

// Thresholds from the brief: a dominant channel above 150, the others below 80 (of 255).
constexpr int kHigh = 150;
constexpr int kLow = 80;

/// An oblique camera with a non-square image, so that swapped axes or a flipped row order
/// put the projected points on the wrong pixels.
Camera ObliqueCamera() {
  Camera camera;
  camera.eye_W = {0.35, -0.9, 0.45};
  camera.target_W = {0.02, 0.05, 0.08};
  camera.up_W = {0.0, 0.0, 1.0};
  camera.fov_y_rad = 0.7;
  camera.width_px = 320;
  camera.height_px = 200;
  camera.near_m = 0.05;
  camera.far_m = 20.0;
  return camera;
}

const std::uint8_t* PixelAt(const ImageRgb8& image, const PixelPoint& p) {
  return image.At(static_cast<int>(std::floor(p.col)), static_cast<int>(std::floor(p.row)));
}

bool IsRed(const std::uint8_t* px) { return px[0] > kHigh && px[1] < kLow && px[2] < kLow; }

/// Red on the shaded parts of a sphere too: clearly lit, and the other channels far below.
bool IsReddish(const std::uint8_t* px) { return px[0] > 60 && px[1] < px[0] / 3 && px[2] < px[0] / 3; }

std::string Describe(const std::uint8_t* px) {
  return "rgb(" + std::to_string(px[0]) + ", " + std::to_string(px[1]) + ", " +
         std::to_string(px[2]) + ")";
}

/// Approximate projected radius [px] of a small sphere at depth (exact at the image centre).
double ProjectedRadius_px(const Camera& camera, double radius_m, double depth_m) {
  return radius_m / depth_m / std::tan(camera.fov_y_rad / 2.0) * camera.height_px / 2.0;
}

/// Mean column of the pixels in [col_begin, col_end) that satisfy `select`.
double MeanColumn(const ImageRgb8& image, int col_begin, int col_end,
                  const std::function<bool(const std::uint8_t*)>& select, int* count) {
  double sum = 0.0;
  *count = 0;
  for (int row = 0; row < image.height_px; ++row) {
    for (int col = col_begin; col < col_end; ++col) {
      if (select(image.At(col, row))) {
        sum += col + 0.5;
        ++*count;
      }
    }
  }
  return *count > 0 ? sum / *count : -1.0;
}

class RenderOffscreen : public ::testing::Test {
 protected:
  OffscreenRenderer renderer_;
};

TEST_F(RenderOffscreen, RedSphereLandsOnItsIndependentlyProjectedPixels) {
  const Camera camera = ObliqueCamera();
  SceneView scene;
  // Off the image centre (upper right of the target), so a mirrored or flipped image fails.
  const Sphere sphere{Eigen::Vector3d(0.15, 0.1, 0.2), 0.03, kRed};
  scene.spheres.push_back(sphere);
  const ImageRgb8 image = renderer_.Render(scene, camera);
  ASSERT_EQ(image.width_px, camera.width_px);
  ASSERT_EQ(image.height_px, camera.height_px);

  const PixelPoint centre = OracleProject(camera, sphere.p_W);
  ASSERT_GT(centre.col, camera.width_px / 2.0) << "the scene set-up should put it right of centre";
  ASSERT_LT(centre.row, camera.height_px / 2.0) << "the scene set-up should put it above centre";
  EXPECT_TRUE(IsRed(PixelAt(image, centre))) << Describe(PixelAt(image, centre));

  // Every pixel well inside the projected disc is (shaded) red, none well outside it is. Margins: the
  // disc radius is approximate off-centre (perspective stretches it by a few percent) and the
  // silhouette is a 48-gon, so test inside 0.7 r and outside 1.3 r + 2 px.
  const double radius_px = ProjectedRadius_px(camera, sphere.radius_m, centre.depth);
  ASSERT_GT(radius_px, 6.0) << "sphere too small in the image for a meaningful test";
  int inside = 0;
  int red_outside = 0;
  for (int row = 0; row < image.height_px; ++row) {
    for (int col = 0; col < image.width_px; ++col) {
      const double r = std::hypot(col + 0.5 - centre.col, row + 0.5 - centre.row);
      const bool red = IsReddish(image.At(col, row));
      if (r < 0.7 * radius_px) {
        ++inside;
        EXPECT_TRUE(red) << "pixel (" << col << ", " << row << ") " << Describe(image.At(col, row));
      } else if (r > 1.3 * radius_px + 2.0 && red) {
        ++red_outside;
      }
    }
  }
  EXPECT_GT(inside, 20);
  EXPECT_EQ(red_outside, 0);
  // The background (a corner, far from the sphere) is not red.
  EXPECT_FALSE(IsRed(image.At(2, image.height_px - 2)));
}

TEST_F(RenderOffscreen, LookingDownAnotherAxisStillMatchesTheOracle) {
  // Camera above the scene looking down -z with up = +y: x to the right, y up in the image.
  Camera camera;
  camera.eye_W = {0.0, 0.0, 2.0};
  camera.target_W = {0.0, 0.0, 0.0};
  camera.up_W = {0.0, 1.0, 0.0};
  camera.fov_y_rad = 0.9;
  camera.width_px = 160;
  camera.height_px = 240;
  SceneView scene;
  scene.grid.visible = false;
  const std::vector<Eigen::Vector3d> centres = {{-0.3, 0.5, 0.0}, {0.25, -0.6, 0.1}};
  for (const auto& p : centres) scene.spheres.push_back({p, 0.06, kRed});
  const ImageRgb8 image = renderer_.Render(scene, camera);
  for (const auto& p : centres) {
    const PixelPoint pixel = OracleProject(camera, p);
    EXPECT_TRUE(IsRed(PixelAt(image, pixel)))
        << "at (" << pixel.col << ", " << pixel.row << "): " << Describe(PixelAt(image, pixel));
  }
  // The first sphere (x < 0, y > 0) is in the upper left quadrant.
  const PixelPoint first = OracleProject(camera, centres[0]);
  EXPECT_LT(first.col, camera.width_px / 2.0);
  EXPECT_LT(first.row, camera.height_px / 2.0);
}

TEST_F(RenderOffscreen, FiveFingertipColoursAreDistinguishable) {
  const Camera camera = ObliqueCamera();
  struct Case {
    Rgb rgb;
    bool r, g, b;  // which channels must dominate
  };
  const std::vector<Case> cases = {{kRed, true, false, false},
                                   {kGreen, false, true, false},
                                   {kBlue, false, false, true},
                                   {kYellow, true, true, false},
                                   {kCyan, false, true, true}};
  SceneView scene;
  std::vector<Eigen::Vector3d> centres;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    centres.emplace_back(-0.2 + 0.1 * static_cast<double>(i), 0.0, 0.1);
    scene.spheres.push_back({centres.back(), 0.025, cases[i].rgb});
  }
  const ImageRgb8 image = renderer_.Render(scene, camera);
  for (std::size_t i = 0; i < cases.size(); ++i) {
    const std::uint8_t* px = PixelAt(image, OracleProject(camera, centres[i]));
    const bool want[3] = {cases[i].r, cases[i].g, cases[i].b};
    for (int channel = 0; channel < 3; ++channel) {
      if (want[channel]) {
        EXPECT_GT(px[channel], kHigh) << "sphere " << i << " channel " << channel << " " << Describe(px);
      } else {
        EXPECT_LT(px[channel], kLow) << "sphere " << i << " channel " << channel << " " << Describe(px);
      }
    }
  }
}

TEST_F(RenderOffscreen, SpheresAreShadedDarkerAwayFromTheLight) {
  Camera camera = ObliqueCamera();
  camera.target_W = {0.0, 0.0, 0.1};
  SceneView scene;
  scene.grid.visible = false;
  const Sphere sphere{camera.target_W, 0.08, kWhite};
  scene.spheres.push_back(sphere);
  const ImageRgb8 image = renderer_.Render(scene, camera);
  const PixelPoint centre = OracleProject(camera, sphere.p_W);
  const double radius_px = ProjectedRadius_px(camera, sphere.radius_m, centre.depth);
  // The light comes from the viewer's upper left: the lower right rim is darker than the centre.
  const int centre_level = PixelAt(image, centre)[0];
  const int rim_level = image.At(static_cast<int>(centre.col + 0.6 * radius_px),
                                 static_cast<int>(centre.row + 0.6 * radius_px))[0];
  EXPECT_GT(centre_level, rim_level + 30) << "centre " << centre_level << ", rim " << rim_level;
  EXPECT_GT(rim_level, 40) << "ambient light keeps the unlit side visible";
}

TEST_F(RenderOffscreen, NearerSphereHidesFartherOne) {
  const Camera camera = ObliqueCamera();
  const Eigen::Vector3d view_W = (camera.target_W - camera.eye_W).normalized();
  SceneView scene;
  // Blue in front of red on the same line of sight; draw red last to catch painter's order.
  scene.spheres.push_back({camera.target_W - 0.2 * view_W, 0.02, kBlue});
  scene.spheres.push_back({camera.target_W, 0.05, kRed});
  const ImageRgb8 image = renderer_.Render(scene, camera);
  const std::uint8_t* px = PixelAt(image, OracleProject(camera, camera.target_W));
  EXPECT_GT(px[2], kHigh) << Describe(px);
  EXPECT_LT(px[0], kLow) << Describe(px);
}

TEST_F(RenderOffscreen, BoxAndMeshAreDrawnAtTheirPoses) {
  const Camera camera = ObliqueCamera();
  SceneView scene;
  scene.grid.visible = false;
  Box box;
  box.p_W = {-0.15, 0.0, 0.1};
  box.half_extents_m = {0.03, 0.03, 0.03};
  box.q_WB = Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ()));
  box.rgb = kGreen;
  scene.boxes.push_back(box);
  // A square in mesh frame M's xz plane, moved by X_WM to the right of the box.
  TriangleMesh mesh;
  mesh.X_WM = Eigen::Translation3d(0.15, 0.0, 0.1) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  mesh.p_MV = {{-0.04, 0.0, -0.04}, {0.04, 0.0, -0.04}, {0.04, 0.0, 0.04}, {-0.04, 0.0, 0.04}};
  mesh.triangles = {{0, 1, 2}, {0, 2, 3}};
  mesh.rgb = kBlue;
  scene.meshes.push_back(mesh);
  const ImageRgb8 image = renderer_.Render(scene, camera);

  const std::uint8_t* box_px = PixelAt(image, OracleProject(camera, box.p_W));
  EXPECT_GT(box_px[1], kHigh) << Describe(box_px);
  EXPECT_LT(box_px[0], kLow) << Describe(box_px);
  const std::uint8_t* mesh_px =
      PixelAt(image, OracleProject(camera, mesh.X_WM * Eigen::Vector3d::Zero()));
  EXPECT_GT(mesh_px[2], kHigh) << Describe(mesh_px);
  EXPECT_LT(mesh_px[0], kLow) << Describe(mesh_px);
  // Just beyond the mesh's right edge (in M) there is no mesh.
  const std::uint8_t* beside =
      PixelAt(image, OracleProject(camera, mesh.X_WM * Eigen::Vector3d(0.07, 0.0, 0.0)));
  EXPECT_LT(beside[2], kHigh) << Describe(beside);
}

TEST_F(RenderOffscreen, MalformedMeshOrCameraIsRejected) {
  SceneView scene;
  TriangleMesh mesh;
  mesh.p_MV = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 3}};
  scene.meshes.push_back(mesh);
  try {
    (void)renderer_.Render(scene, ObliqueCamera());
    FAIL() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("meshes[0]: triangle 0 refers to vertex 3"), std::string::npos)
        << e.what();
  }
  scene.meshes[0].triangles = {{0, 1, 2}};
  scene.meshes[0].n_MV = {{0, 0, 1}};
  EXPECT_THROW((void)renderer_.Render(scene, ObliqueCamera()), std::invalid_argument);

  Camera camera = ObliqueCamera();
  camera.target_W = camera.eye_W;
  EXPECT_THROW((void)renderer_.Render(SceneView{}, camera), std::invalid_argument);
}

// Caption pixels: bright (all channels > 200) in the bottom band.
int CountCaptionPixels(const ImageRgb8& image, int row_begin, int row_end) {
  int count = 0;
  for (int row = row_begin; row < row_end; ++row) {
    for (int col = 0; col < image.width_px; ++col) {
      const std::uint8_t* px = image.At(col, row);
      if (px[0] > 200 && px[1] > 200 && px[2] > 200) ++count;
    }
  }
  return count;
}

// Bright pixels within columns [col_begin, col_end) of rows [row_begin, row_end).
int CountBrightPixels(const ImageRgb8& image, int row_begin, int row_end, int col_begin, int col_end) {
  int count = 0;
  for (int row = row_begin; row < row_end; ++row) {
    for (int col = col_begin; col < col_end; ++col) {
      const std::uint8_t* px = image.At(col, row);
      if (px[0] > 200 && px[1] > 200 && px[2] > 200) ++count;
    }
  }
  return count;
}

TEST_F(RenderOffscreen, OverlayIsDrawnAtTheTopLeftOnlyWhenPresent) {
  Camera camera = ObliqueCamera();
  camera.width_px = 640;
  camera.height_px = 480;
  SceneView scene;
  scene.grid.visible = false;
  const int w = camera.width_px, h = camera.height_px;
  EXPECT_EQ(CountBrightPixels(renderer_.Render(scene, camera), 0, h, 0, w), 0);
  scene.overlay = "mouse: hand left/right, up/down\nwheel or W/S: away / towards you\nforces [N]: thumb 0.00";
  const ImageRgb8 with = renderer_.Render(scene, camera);
  // Three lines of 12 px text in the top-left quarter, nothing elsewhere.
  EXPECT_GT(CountBrightPixels(with, 0, h / 4, 0, w / 2), 150);  // 292 seen
  EXPECT_EQ(CountBrightPixels(with, h / 4, h, 0, w), 0);
  EXPECT_EQ(CountBrightPixels(with, 0, h, w / 2, w), 0);
}

TEST_F(RenderOffscreen, CaptionIsDrawnAtTheBottomOnlyWhenPresent) {
  Camera camera = ObliqueCamera();
  camera.width_px = 480;
  camera.height_px = 480;  // em height 16 px: one line and its band take about 40 px
  SceneView scene;
  scene.grid.visible = false;
  const int band_top = camera.height_px - 48;

  const ImageRgb8 without = renderer_.Render(scene, camera);
  EXPECT_EQ(CountCaptionPixels(without, 0, camera.height_px), 0);
  EXPECT_EQ(renderer_.last_caption().lines, 0);

  scene.caption = "Welcome to the solar system";
  const ImageRgb8 with = renderer_.Render(scene, camera);
  const int text_pixels = CountCaptionPixels(with, band_top, camera.height_px);
  EXPECT_GT(text_pixels, 200);
  EXPECT_EQ(CountCaptionPixels(with, 0, band_top), 0) << "caption must stay in the bottom band";
  EXPECT_EQ(renderer_.last_caption().lines, 1);
  EXPECT_EQ(renderer_.last_caption().glyphs, 23);
  // The band darkens the background under it.
  EXPECT_LT(with.At(camera.width_px - 3, camera.height_px - 3)[2],
            without.At(camera.width_px - 3, camera.height_px - 3)[2]);

  // Different text, different pixels.
  scene.caption = "iiiiiiiiii";
  const int thin = CountCaptionPixels(renderer_.Render(scene, camera), band_top, camera.height_px);
  scene.caption = "WWWWWWWWWW";
  const int wide = CountCaptionPixels(renderer_.Render(scene, camera), band_top, camera.height_px);
  EXPECT_LT(thin, wide);

  // Text longer than a line wraps upwards, and far too much is cut at a third of the image.
  scene.caption = std::string(1000, 'M');
  const ImageRgb8 cut = renderer_.Render(scene, camera);
  EXPECT_TRUE(renderer_.last_caption().cut);
  EXPECT_GT(renderer_.last_caption().lines, 1);
  EXPECT_EQ(CountCaptionPixels(cut, 0, camera.height_px * 2 / 3), 0);
  EXPECT_GT(CountCaptionPixels(cut, camera.height_px * 2 / 3, camera.height_px), 3 * text_pixels);
}

// The board in Japanese: its caption is drawn in the font's own glyphs (no empty boxes) and
// differs from the English one in the same frame.
TEST_F(RenderOffscreen, AJapaneseCaptionHasGlyphsAndDiffersFromTheEnglishOne) {
  Camera camera = ObliqueCamera();
  camera.width_px = 960;
  camera.height_px = 540;
  SceneView scene;
  scene.grid.visible = false;
  scene.caption = "You are on the Moon. Gravity here is one sixth of the Earth's.";
  const ImageRgb8 english = renderer_.Render(scene, camera);
  EXPECT_EQ(renderer_.last_caption().missing_glyphs, 0);
  scene.caption = "ここは月です。重力は地球の約6分の1です。";
  const ImageRgb8 japanese = renderer_.Render(scene, camera);
  EXPECT_EQ(renderer_.last_caption().missing_glyphs, 0);
  EXPECT_EQ(renderer_.last_caption().glyphs, 21);
  const int band_top = camera.height_px * 2 / 3;
  const int ja_pixels = CountCaptionPixels(japanese, band_top, camera.height_px);
  EXPECT_GT(ja_pixels, 21 * 20) << "every glyph has ink";
  int differ = 0;
  for (int row = band_top; row < camera.height_px; ++row) {
    for (int col = 0; col < camera.width_px; ++col) {
      differ += std::abs(japanese.At(col, row)[0] - english.At(col, row)[0]) > 64 ? 1 : 0;
    }
  }
  EXPECT_GT(differ, ja_pixels / 2);
  // A character the font lacks is still drawn, as a box, and reported.
  scene.caption = "\xF0\x9F\xA6\x96";
  (void)renderer_.Render(scene, camera);
  EXPECT_EQ(renderer_.last_caption().missing_glyphs, 1);
}

// Looking straight down at the table (z = 0) from 20 cm, y up in the image.
Camera AboveTheTable(int size_px) {
  Camera camera;
  camera.eye_W = {0.0, 0.0, 0.2};
  camera.target_W = {0.0, 0.0, 0.0};
  camera.up_W = {0.0, 1.0, 0.0};
  camera.width_px = size_px;
  camera.height_px = size_px;
  camera.near_m = 0.01;
  camera.far_m = 10.0;
  return camera;
}

// A page (a book's open spread) lies flat on the table, seen from above: its picture is drawn
// where its quad projects, above its text, on paper; without text the text band is blank; a box
// in front of it hides it.
TEST_F(RenderOffscreen, APageShowsItsPictureAboveItsTextWhereItsQuadProjects) {
  const Camera camera = AboveTheTable(400);
  SceneView scene;
  scene.grid.visible = false;
  scene.background_rgb = {0.0F, 0.0F, 0.3F};
  Page page;
  page.corners_W = {Eigen::Vector3d(-0.05, -0.07, 0.0), Eigen::Vector3d(0.05, -0.07, 0.0),
                    Eigen::Vector3d(0.05, 0.07, 0.0), Eigen::Vector3d(-0.05, 0.07, 0.0)};
  auto red = std::make_shared<ImageRgb8>(4, 4);
  for (std::size_t i = 0; i < red->rgb.size(); i += 3) red->rgb[i] = 255;
  page.image = red;
  page.text = "The Moon and Mars pull on everything less than the Earth does.";
  scene.pages.push_back(page);
  // Where the page's texture pixel (x, y) of 256 x 358 lands (row 0 at the page's top edge).
  const auto at = [&](double x, double y) {
    const Eigen::Vector3d p_W(-0.05 + 0.1 * x / 256.0, 0.07 - 0.14 * y / 358.0, 0.0);
    return OracleProject(camera, p_W);
  };
  const auto dark = [](const std::uint8_t* px) { return px[0] < 110 && px[1] < 110 && px[2] < 110; };
  const auto ink_in_text_band = [&](const ImageRgb8& image) {
    // The text starts below the picture (rows 16 .. 214 of the texture) and its margin.
    const PixelPoint top_left = at(16, 226);
    const PixelPoint bottom_right = at(240, 342);
    int n = 0;
    for (int row = static_cast<int>(top_left.row); row < static_cast<int>(bottom_right.row); ++row) {
      for (int col = static_cast<int>(top_left.col); col < static_cast<int>(bottom_right.col); ++col) {
        n += dark(image.At(col, row)) ? 1 : 0;
      }
    }
    return n;
  };

  const ImageRgb8 image = renderer_.Render(scene, camera);
  const std::uint8_t* picture = PixelAt(image, at(128, 115));
  EXPECT_TRUE(IsRed(picture)) << Describe(picture);
  const std::uint8_t* paper = PixelAt(image, at(6, 179));  // in the left margin
  EXPECT_GT(paper[0], 220) << Describe(paper);
  EXPECT_GT(paper[1], 210) << Describe(paper);
  EXPECT_GT(paper[2], 190) << Describe(paper);
  const std::uint8_t* outside = PixelAt(image, OracleProject(camera, Eigen::Vector3d(0.08, 0.0, 0.0)));
  EXPECT_LT(outside[0], 20) << "beside the page, the background: " << Describe(outside);
  const int ink = ink_in_text_band(image);
  EXPECT_GT(ink, 300) << "the text's ink";

  scene.pages[0].text.clear();
  EXPECT_EQ(ink_in_text_band(renderer_.Render(scene, camera)), 0) << "no text, no ink";

  // A red box 5 cm above the page's middle hides it there.
  scene.pages[0].image = nullptr;
  Box box;
  box.p_W = {0.0, 0.0, 0.05};
  box.half_extents_m = {0.02, 0.02, 0.005};
  box.rgb = kGreen;
  scene.boxes.push_back(box);
  const std::uint8_t* hidden = PixelAt(renderer_.Render(scene, camera), at(128, 179));
  EXPECT_GT(hidden[1], kHigh) << Describe(hidden);
  EXPECT_LT(hidden[0], kLow) << Describe(hidden);
}

// A page's texture is uploaded once and drawn again from the renderer's texture object while
// the page shows the same content (the start menu's two pages were uploaded every frame, most of
// its p99). What is drawn stays what a fresh renderer draws: a page turned shows its new
// content, and turned back its old one, from the kept object.
TEST_F(RenderOffscreen, APageIsUploadedOnceAndDrawnAgainAsAFreshRendererDrawsIt) {
  const Camera camera = AboveTheTable(200);
  SceneView scene;
  scene.grid.visible = false;
  Page left, right;
  left.corners_W = {Eigen::Vector3d(-0.1, -0.07, 0.0), Eigen::Vector3d(0.0, -0.07, 0.0),
                    Eigen::Vector3d(0.0, 0.07, 0.0), Eigen::Vector3d(-0.1, 0.07, 0.0)};
  right.corners_W = {Eigen::Vector3d(0.0, -0.07, 0.0), Eigen::Vector3d(0.1, -0.07, 0.0),
                     Eigen::Vector3d(0.1, 0.07, 0.0), Eigen::Vector3d(0.0, 0.07, 0.0)};
  left.text = "Page one: the Moon.";
  right.text = "Page two: Mars.";
  scene.pages = {left, right};
  const auto fresh = [&](const SceneView& s) {
    OffscreenRenderer r;
    return r.Render(s, camera);
  };
  const ImageRgb8 first = renderer_.Render(scene, camera);
  EXPECT_EQ(renderer_.page_uploads(), 2u);
  for (int frame = 0; frame < 3; ++frame) {
    const ImageRgb8 again = renderer_.Render(scene, camera);
    EXPECT_EQ(again.rgb, first.rgb) << "frame " << frame;
  }
  EXPECT_EQ(renderer_.page_uploads(), 2u) << "drawn again, not uploaded again";
  EXPECT_EQ(first.rgb, fresh(scene).rgb);

  SceneView turned = scene;
  turned.pages[1].text = "Page three: the triceratops.";
  const ImageRgb8 after = renderer_.Render(turned, camera);
  EXPECT_EQ(renderer_.page_uploads(), 3u);
  EXPECT_NE(after.rgb, first.rgb);
  EXPECT_EQ(after.rgb, fresh(turned).rgb) << "the turned page shows its new text";
  EXPECT_EQ(renderer_.Render(scene, camera).rgb, first.rgb) << "turned back: the old page, from its object";
  EXPECT_EQ(renderer_.page_uploads(), 3u);
}

// A label is drawn just above its point's projection, in its colour on a darkened box; not at
// all when its point is behind the eye or outside the image; a fingertip marker in front of it
// stays visible (markers are drawn after the labels).
TEST_F(RenderOffscreen, ALabelIsDrawnAboveItsPointAndUnderTheFingertips) {
  Camera camera = ObliqueCamera();
  camera.width_px = 480;
  camera.height_px = 360;
  SceneView scene;
  scene.grid.visible = false;
  scene.background_rgb = {0.3F, 0.3F, 0.3F};
  const Eigen::Vector3d point(0.02, 0.05, 0.08);
  const PixelPoint at = OracleProject(camera, point);
  const auto count = [](const ImageRgb8& image, int col0, int col1, int row0, int row1, auto&& test) {
    int n = 0;
    for (int row = std::max(0, row0); row < std::min(image.height_px, row1); ++row) {
      for (int col = std::max(0, col0); col < std::min(image.width_px, col1); ++col) n += test(image.At(col, row)) ? 1 : 0;
    }
    return n;
  };
  // The label colour (1, 0.93, 0.6): (255, 237, 153) where a glyph covers a pixel fully.
  const auto yellowish = [](const std::uint8_t* px) { return px[0] > 170 && px[1] > 160 && px[0] > px[2] + 40; };
  const auto darkened = [](const std::uint8_t* px) { return px[0] < 60 && px[1] < 60 && px[2] < 60; };
  const int c0 = static_cast<int>(at.col) - 80;
  const int c1 = static_cast<int>(at.col) + 80;
  const int r = static_cast<int>(at.row);

  const ImageRgb8 without = renderer_.Render(scene, camera);
  EXPECT_EQ(count(without, 0, camera.width_px, 0, camera.height_px, yellowish), 0);
  Label label;
  label.p_W = point;
  label.text = "Tail";
  scene.labels.push_back(label);
  const ImageRgb8 with = renderer_.Render(scene, camera);
  const int above = count(with, c0, c1, r - 40, r, yellowish);
  EXPECT_GT(above, 20) << "the text, above its point";
  EXPECT_GT(count(with, c0, c1, r - 40, r, darkened), 50) << "on a darkened box";
  EXPECT_EQ(count(with, 0, camera.width_px, r + 2, camera.height_px, yellowish), 0) << "nothing below its point";

  // A fingertip in front of the label, between it and the eye: drawn over it.
  const Eigen::Vector3d near_label = camera.eye_W + 0.5 * (point + Eigen::Vector3d(0.0, 0.0, 0.012) - camera.eye_W);
  scene.markers.push_back(Sphere{near_label, 0.004, kRed});
  const ImageRgb8 marked = renderer_.Render(scene, camera);
  const std::uint8_t* tip = PixelAt(marked, OracleProject(camera, near_label));
  EXPECT_TRUE(IsRed(tip)) << Describe(tip);
  scene.markers.clear();

  // Behind the eye, or outside the image: no label.
  scene.labels[0].p_W = camera.eye_W - (camera.target_W - camera.eye_W);
  EXPECT_EQ(count(renderer_.Render(scene, camera), 0, camera.width_px, 0, camera.height_px, yellowish), 0);
  scene.labels[0].p_W = point + Eigen::Vector3d(5.0, 0.0, 0.0);
  EXPECT_EQ(count(renderer_.Render(scene, camera), 0, camera.width_px, 0, camera.height_px, yellowish), 0);
}

// Appearance: a translucent box in front of a red sphere lets it show through (an opaque one
// hides it); a specular sphere is brighter than a matte one of its colour somewhere (its
// highlight) and the same elsewhere.
TEST_F(RenderOffscreen, TranslucentObjectsShowWhatIsBehindThemAndSpecularOnesShine) {
  Camera camera = ObliqueCamera();
  SceneView scene;
  scene.grid.visible = false;
  const Sphere red{Eigen::Vector3d(0.02, 0.05, 0.08), 0.03, kRed};
  scene.spheres.push_back(red);
  Box pane;
  pane.p_W = camera.eye_W + 0.5 * (red.p_W - camera.eye_W);  // halfway to the eye
  pane.half_extents_m = {0.05, 0.05, 0.05};
  pane.rgb = kBlue;
  scene.boxes.push_back(pane);
  const PixelPoint at = OracleProject(camera, red.p_W);
  const std::uint8_t* hidden = PixelAt(renderer_.Render(scene, camera), at);
  EXPECT_LT(hidden[0], kLow) << "behind an opaque box: " << Describe(hidden);
  SceneView bare = scene;
  bare.boxes.clear();
  const int direct = PixelAt(renderer_.Render(bare, camera), at)[0];
  scene.boxes[0].look.opacity = 0.4F;
  const ImageRgb8 through = renderer_.Render(scene, camera);
  const std::uint8_t* seen = PixelAt(through, at);
  // Through both faces of the pane: (1 - 0.4)^2 = 0.36 of the sphere's red, and blue of the pane.
  EXPECT_NEAR(seen[0], 0.36 * direct, 0.05 * direct) << "red through the pane: " << Describe(seen);
  EXPECT_GT(seen[2], 40) << "and some of the pane's blue: " << Describe(seen);

  SceneView balls;
  balls.grid.visible = false;
  balls.spheres.push_back(Sphere{Eigen::Vector3d(0.02, 0.05, 0.08), 0.04, Rgb{0.5F, 0.5F, 0.5F}});
  const ImageRgb8 matte = renderer_.Render(balls, camera);
  balls.spheres[0].look.specular = 1.0F;
  balls.spheres[0].look.shininess = 40.0F;
  const ImageRgb8 shiny = renderer_.Render(balls, camera);
  int brighter = 0;
  int brightest = 0;
  for (int row = 0; row < camera.height_px; ++row) {
    for (int col = 0; col < camera.width_px; ++col) {
      const int d = shiny.At(col, row)[1] - matte.At(col, row)[1];
      EXPECT_GE(d, 0) << "a highlight only adds light, at (" << col << ", " << row << ")";
      brighter += d > 30 ? 1 : 0;
      brightest = std::max(brightest, d);
    }
  }
  EXPECT_GT(brighter, 10) << "a highlight";
  EXPECT_GT(brightest, 80);
  const std::uint8_t* edge = PixelAt(shiny, OracleProject(camera, Eigen::Vector3d(0.02, 0.05, 0.08) + Eigen::Vector3d(0.0, 0.0, -0.038)));
  const std::uint8_t* edge_matte = PixelAt(matte, OracleProject(camera, Eigen::Vector3d(0.02, 0.05, 0.08) + Eigen::Vector3d(0.0, 0.0, -0.038)));
  EXPECT_NEAR(edge[1], edge_matte[1], 3) << "away from the highlight, the same";
}

TEST_F(RenderOffscreen, SideBySideStereoShiftsNearAndFarSpheresOppositeWays) {
  Camera camera = ObliqueCamera();
  camera.stereo_eye_separation_m = 0.1;  // exaggerated so the disparity is many pixels
  const Eigen::Vector3d view_W = (camera.target_W - camera.eye_W).normalized();
  const double focal_m = (camera.target_W - camera.eye_W).norm();

  for (const double depth_change_m : {-0.4, 0.5}) {  // nearer, then farther than the focal plane
    SCOPED_TRACE(depth_change_m < 0 ? "near sphere" : "far sphere");
    SceneView scene;
    scene.grid.visible = false;
    const Eigen::Vector3d p_W = camera.target_W + depth_change_m * view_W;
    scene.spheres.push_back({p_W, 0.03, kRed});
    const ImageRgb8 image = renderer_.Render(scene, camera, StereoMode::kSideBySide);
    ASSERT_EQ(image.width_px, 2 * camera.width_px);
    ASSERT_EQ(image.height_px, camera.height_px);

    // Each half shows the sphere where the off-axis oracle puts it for that eye.
    const double e = camera.stereo_eye_separation_m / 2.0;
    const PixelPoint left = OracleProject(camera, p_W, -e);
    PixelPoint right = OracleProject(camera, p_W, +e);
    EXPECT_TRUE(IsRed(PixelAt(image, left))) << Describe(PixelAt(image, left));
    right.col += camera.width_px;
    EXPECT_TRUE(IsRed(PixelAt(image, right))) << Describe(PixelAt(image, right));

    // Measured from the pixels alone: nearer than the focal plane shifts left in the right
    // eye (crossed disparity), farther shifts right.
    int left_count = 0;
    int right_count = 0;
    const double left_col = MeanColumn(image, 0, camera.width_px, IsRed, &left_count);
    const double right_col =
        MeanColumn(image, camera.width_px, 2 * camera.width_px, IsRed, &right_count) - camera.width_px;
    ASSERT_GT(left_count, 20);
    ASSERT_GT(right_count, 20);
    const double disparity_px = right_col - left_col;
    const double depth_m = focal_m + depth_change_m;
    // Expected disparity from the convention: (c / aspect) * sep * (1/d - 1/depth) * width / 2.
    const double aspect = static_cast<double>(camera.width_px) / camera.height_px;
    const double expected_px = 1.0 / std::tan(camera.fov_y_rad / 2.0) / aspect *
                               camera.stereo_eye_separation_m * (1.0 / focal_m - 1.0 / depth_m) *
                               camera.width_px / 2.0;
    if (depth_change_m < 0) {
      EXPECT_LT(disparity_px, -3.0);
    } else {
      EXPECT_GT(disparity_px, 3.0);
    }
    // Centroids of a projected sphere are off its centre's projection by a fraction of a pixel.
    EXPECT_NEAR(disparity_px, expected_px, 1.0);
  }
}

TEST_F(RenderOffscreen, SphereAtTheFocalDistanceHasNoDisparity) {
  Camera camera = ObliqueCamera();
  camera.stereo_eye_separation_m = 0.1;
  SceneView scene;
  scene.grid.visible = false;
  scene.spheres.push_back({camera.target_W, 0.03, kRed});
  const ImageRgb8 image = renderer_.Render(scene, camera, StereoMode::kSideBySide);
  int left_count = 0;
  int right_count = 0;
  const double left_col = MeanColumn(image, 0, camera.width_px, IsRed, &left_count);
  const double right_col =
      MeanColumn(image, camera.width_px, 2 * camera.width_px, IsRed, &right_count) - camera.width_px;
  ASSERT_GT(left_count, 20);
  EXPECT_NEAR(right_col, left_col, 0.5);
}

TEST_F(RenderOffscreen, AnaglyphPutsLeftEyeInRedAndRightEyeInCyan) {
  Camera camera = ObliqueCamera();
  camera.stereo_eye_separation_m = 0.1;
  const Eigen::Vector3d view_W = (camera.target_W - camera.eye_W).normalized();
  SceneView scene;
  scene.grid.visible = false;
  scene.background_rgb = {0.0F, 0.0F, 0.0F};
  const Eigen::Vector3d p_W = camera.target_W - 0.4 * view_W;  // nearer than the focal plane
  scene.spheres.push_back({p_W, 0.03, kWhite});
  const ImageRgb8 image = renderer_.Render(scene, camera, StereoMode::kAnaglyph);
  ASSERT_EQ(image.width_px, camera.width_px);
  ASSERT_EQ(image.height_px, camera.height_px);

  int red_count = 0;
  int cyan_count = 0;
  const double red_col =
      MeanColumn(image, 0, image.width_px, [](const std::uint8_t* px) { return px[0] > 100; }, &red_count);
  const double cyan_col = MeanColumn(
      image, 0, image.width_px, [](const std::uint8_t* px) { return px[1] > 100 && px[2] > 100; },
      &cyan_count);
  ASSERT_GT(red_count, 20);
  ASSERT_GT(cyan_count, 20);
  // Near object: the right eye (cyan) sees it further left than the left eye (red).
  EXPECT_LT(cyan_col, red_col - 3.0);
  // At the left eye's oracle pixel, red is present.
  const double e = camera.stereo_eye_separation_m / 2.0;
  EXPECT_GT(PixelAt(image, OracleProject(camera, p_W, -e))[0], kHigh);
  EXPECT_GT(PixelAt(image, OracleProject(camera, p_W, +e))[1], kHigh);
}

TEST_F(RenderOffscreen, RendererIsReusableAcrossSizes) {
  Camera camera = ObliqueCamera();
  SceneView scene;
  scene.spheres.push_back({camera.target_W, 0.03, kRed});
  for (const auto& [w, h] : {std::pair{64, 48}, std::pair{300, 500}, std::pair{64, 48}}) {
    camera.width_px = w;
    camera.height_px = h;
    const ImageRgb8 image = renderer_.Render(scene, camera);
    ASSERT_EQ(image.width_px, w);
    ASSERT_EQ(image.height_px, h);
    EXPECT_TRUE(IsRed(PixelAt(image, OracleProject(camera, camera.target_W))));
  }
}

}  // namespace
}  // namespace handshare::render
