// A page's texture: the picture fitted above the text, the text in the caption font, and the
// cache that keeps a page's texture while it shows the same thing.
#include "page_texture.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>

namespace handshare::render::detail {
namespace {

Page ABookPage(const std::string& text) {
  Page page;
  page.corners_W = {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(0.10, 0.0, 0.0),
                    Eigen::Vector3d(0.10, 0.14, 0.0), Eigen::Vector3d(0.0, 0.14, 0.0)};
  page.text = text;
  return page;
}

int Inked(const PageTexture& t, int row_begin, int row_end) {  // pixels darker than the paper
  int n = 0;
  for (int y = row_begin; y < row_end; ++y) {
    for (int x = 0; x < t.width_px; ++x) n += t.At(x, y)[0] < 150 ? 1 : 0;
  }
  return n;
}

TEST(PageTexture, ItsHeightFollowsThePagesAspect) {
  EXPECT_EQ(PageTextureHeight(ABookPage("")), 358);  // 14 / 10 of 256
  Page flat = ABookPage("");
  flat.corners_W[3] = flat.corners_W[0];  // no height at all
  EXPECT_EQ(PageTextureHeight(flat), 64);  // clamped to a quarter of the width
  Page point;
  point.corners_W.fill(Eigen::Vector3d::Zero());
  EXPECT_EQ(PageTextureHeight(point), 256);
}

TEST(PageTexture, ThePictureIsFittedAboveTheText) {
  CaptionFont font(DefaultCaptionFont());
  Page page = ABookPage("Triceratops lived 68 to 66 million years ago.");
  auto blue = std::make_shared<ImageRgb8>(8, 4);  // twice as wide as high
  for (std::size_t i = 2; i < blue->rgb.size(); i += 3) blue->rgb[i] = 255;
  page.image = blue;
  const PageTexture t = ComposePage(&font, page, 256, 358);
  ASSERT_EQ(t.rgb.size(), 3U * 256 * 358);
  // 224 px wide (the width less two 16 px margins), so 112 px high, from row 16.
  EXPECT_EQ(t.At(128, 20)[2], 255);
  EXPECT_EQ(t.At(128, 20)[0], 0);
  EXPECT_EQ(t.At(20, 72)[0], 0) << "the picture spans the width inside the margins";
  EXPECT_NE(t.At(8, 72)[0], 0) << "the margin is paper";
  EXPECT_NE(t.At(128, 132)[0], 0) << "below the picture, paper";
  EXPECT_GT(t.text.glyphs, 30);
  EXPECT_EQ(t.text.missing_glyphs, 0);
  EXPECT_FALSE(t.text.cut);
  EXPECT_GT(Inked(t, 136, 358), 400) << "the text is below the picture";
  EXPECT_EQ(Inked(t, 0, 16), 0) << "nothing in the top margin";
}

TEST(PageTexture, JapaneseTextHasItsGlyphsAndTooMuchTextIsCut) {
  CaptionFont font(DefaultCaptionFont());
  const PageTexture ja = ComposePage(&font, ABookPage("月でボールを持ち上げてみましょう。"), 256, 358);
  EXPECT_EQ(ja.text.missing_glyphs, 0);
  EXPECT_EQ(ja.text.glyphs, 17);
  const PageTexture full = ComposePage(&font, ABookPage(std::string(3000, 'M')), 256, 358);
  EXPECT_TRUE(full.text.cut);
  EXPECT_GT(full.text.lines, 10);
  EXPECT_EQ(Inked(full, 358 - 8, 358), 0) << "the bottom margin stays paper";
}

TEST(PageTexture, APageWithoutTextNeedsNoFont) {
  Page page = ABookPage("");
  page.image = std::make_shared<ImageRgb8>(2, 2);  // black
  const PageTexture t = ComposePage(nullptr, page, 256, 358);
  EXPECT_EQ(t.At(128, 179)[0], 0) << "without text the picture takes the whole page";
  EXPECT_EQ(t.text.lines, 0);
}

TEST(PageCache, APageDrawnAgainIsNotComposedAgain) {
  PageCache cache;
  const Page a = ABookPage("page one");
  const Page b = ABookPage("page two");
  const PageTexture* first = &cache.For(a);
  EXPECT_EQ(cache.composed(), 1U);
  EXPECT_EQ(&cache.For(a), first);
  EXPECT_EQ(cache.composed(), 1U);
  (void)cache.For(b);
  EXPECT_EQ(cache.composed(), 2U);
  Page inked = a;
  inked.ink = {1.0F, 0.0F, 0.0F};
  (void)cache.For(inked);
  EXPECT_EQ(cache.composed(), 3U) << "another colour is another texture";
  // More pages than it keeps: the one drawn longest ago is composed again.
  for (int i = 0; i < static_cast<int>(PageCache::kEntries); ++i) (void)cache.For(ABookPage("more " + std::to_string(i)));
  const std::uint64_t before = cache.composed();
  (void)cache.For(b);
  EXPECT_EQ(cache.composed(), before + 1);
}

}  // namespace
}  // namespace handshare::render::detail
