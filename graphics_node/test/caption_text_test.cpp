#include "caption_text.hpp"

#include <gtest/gtest.h>

#include <string>

#include "handshare/common/utf8.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::render::detail {
namespace {

int Ink(const CaptionBitmap& b, int x0 = 0, int x1 = -1) {
  if (x1 < 0) x1 = b.width_px;
  int n = 0;
  for (int y = 0; y < b.height_px; ++y) {
    for (int x = x0; x < x1; ++x) n += b.At(x, y) > 128 ? 1 : 0;
  }
  return n;
}

int Printed(const std::string& text) {  // code points that are neither spaces nor line breaks
  int n = 0;
  for (const char32_t c : common::DecodeUtf8(text)) n += (c != U' ' && c != U'\n' && c != 0x3000) ? 1 : 0;
  return n;
}

class CaptionText : public ::testing::Test {
 protected:
  CaptionFont font_{DefaultCaptionFont()};
};

// Every board text of the project, English and Japanese, is drawn with the font's own glyphs:
// no character falls back to an empty box.
TEST_F(CaptionText, EveryBoardTextOfTheScenesHasItsGlyphs) {
  int japanese = 0;
  for (const std::string& name : scene::SceneNames(HANDSHARE_SOURCE_SCENES)) {
    const scene::Scene s = scene::LoadSceneByName(name, HANDSHARE_SOURCE_SCENES);
    for (const scene::Message& m : scene::AllMessages(s)) {
      const std::string text = m.text + (m.next_action.empty() ? "" : "\n" + m.next_action);
      const CaptionBitmap b = font_.Layout(text, 24, 900, 20);
      EXPECT_EQ(b.stats.missing_glyphs, 0) << name << ": " << text;
      EXPECT_EQ(b.stats.glyphs, Printed(text)) << name << ": " << text;
      EXPECT_FALSE(b.stats.cut) << name;
      EXPECT_GT(Ink(b), 20 * b.stats.glyphs) << name << ": glyphs with ink, at 24 px";
      japanese += m.language == "ja" ? 1 : 0;
    }
  }
  EXPECT_EQ(japanese, 12);
}

// The same for the text printed on the books' pages.
TEST_F(CaptionText, EveryPageTextOfTheBooksHasItsGlyphs) {
  int texts = 0;
  const scene::Scene s = scene::LoadSceneByName("start_menu", HANDSHARE_SOURCE_SCENES);
  for (const auto& c : s.controls) {
    for (const auto& page : c.page_content) {
      for (const auto& t : page.text) {
        const CaptionBitmap b = font_.Layout(t.text, 20, 300, 20);
        EXPECT_EQ(b.stats.missing_glyphs, 0) << c.id << ": " << t.text;
        EXPECT_EQ(b.stats.glyphs, Printed(t.text)) << c.id << ": " << t.text;
        ++texts;
      }
    }
  }
  EXPECT_EQ(texts, 12);  // three books, two pages each, in English and Japanese
}

TEST_F(CaptionText, WrapsAtSpacesAndBetweenJapaneseCharacters) {
  const std::string english = "Press a part of the triceratops with your partner, or pass the ball.";
  const CaptionBitmap one = font_.Layout(english, 20, 2000, 10);
  EXPECT_EQ(one.stats.lines, 1);
  const CaptionBitmap wrapped = font_.Layout(english, 20, 200, 10);
  EXPECT_GE(wrapped.stats.lines, 3);
  EXPECT_LE(wrapped.width_px, 200);
  EXPECT_EQ(wrapped.stats.glyphs, one.stats.glyphs) << "wrapping loses no character";
  // Its lines' height, and what the last line's descenders reach below it (less than a line).
  const int line_px = font_.Layout("ace", 20, 2000, 10).height_px;
  EXPECT_GE(wrapped.height_px, wrapped.stats.lines * line_px);
  EXPECT_LT(wrapped.height_px, (wrapped.stats.lines + 1) * line_px);

  // Japanese has no spaces: it wraps between any two characters, never before 、 or 。.
  const std::string japanese = "パートナーと一緒にトリケラトプスを押すか、ボールを渡してください。";
  const CaptionBitmap ja = font_.Layout(japanese, 20, 100, 20);  // five characters a line
  EXPECT_GE(ja.stats.lines, 6);
  EXPECT_LE(ja.width_px, 100);
  EXPECT_EQ(ja.stats.glyphs, Printed(japanese));

  // A paragraph break starts a line; a word longer than the line is cut, not lost.
  EXPECT_EQ(font_.Layout("one\ntwo", 20, 2000, 10).stats.lines, 2);
  const CaptionBitmap word = font_.Layout(std::string(40, 'W'), 20, 200, 10);
  EXPECT_GE(word.stats.lines, 3);
  EXPECT_EQ(word.stats.glyphs, 40);
}

TEST_F(CaptionText, TooMuchTextIsCutWithAnEllipsis) {
  std::string text;
  for (int i = 0; i < 60; ++i) text += "lever ";
  const CaptionBitmap b = font_.Layout(text, 20, 300, 2);
  EXPECT_EQ(b.stats.lines, 2);
  EXPECT_TRUE(b.stats.cut);
  EXPECT_LT(b.stats.glyphs, 300);
  EXPECT_FALSE(font_.Layout("lever", 20, 300, 2).stats.cut);
}

TEST_F(CaptionText, ACharacterTheFontLacksIsAVisibleBox) {
  ASSERT_FALSE(font_.HasGlyph(0x1F996));  // a sauropod emoji: not in IPA Gothic
  ASSERT_TRUE(font_.HasGlyph(U'恐'));
  const CaptionBitmap b = font_.Layout("a\xF0\x9F\xA6\x96" "b", 24, 900, 2);
  EXPECT_EQ(b.stats.missing_glyphs, 1);
  EXPECT_EQ(b.stats.glyphs, 2);
  const CaptionBitmap ab = font_.Layout("ab", 24, 900, 2);
  EXPECT_GT(b.width_px, ab.width_px + 10);
  EXPECT_GT(Ink(b), Ink(ab) + 30) << "the box has ink";
}

int TotalCoverage(const CaptionBitmap& b) {
  int n = 0;
  for (const std::uint8_t c : b.coverage) n += c;
  return n;
}

// A glyph that reaches past its line (a descender below the font's descent, a ring above its
// ascent: IPA Gothic's line height is exactly its em) is drawn whole: the bitmap grows to hold
// it. The oracle: the same line between two blank lines, where there is room, has the same ink.
// Before, the first and last lines were cut at the bitmap's edges (the caption's last line
// then seemed to sit on the bottom of its band).
TEST_F(CaptionText, GlyphsReachingPastTheirLineAreDrawnWhole) {
  for (const int pixel_size : {12, 16, 20, 27, 36}) {
    for (const std::string text : {"Ågjpqy", "ÅÉ|", "gjpqy()", "ぎゃ、。Åg"}) {
      const CaptionBitmap alone = font_.Layout(text, pixel_size, 4000, 3);
      const CaptionBitmap roomy = font_.Layout(" \n" + text + "\n ", pixel_size, 4000, 3);
      ASSERT_EQ(roomy.stats.lines, 3);
      EXPECT_EQ(TotalCoverage(alone), TotalCoverage(roomy)) << "'" << text << "' at " << pixel_size << " px";
      EXPECT_GE(alone.height_px, pixel_size);  // at least its line
    }
  }
  // Where nothing reaches past its lines, the bitmap is the lines' height, as before.
  const CaptionBitmap plain = font_.Layout("ace", 16, 4000, 3);
  EXPECT_EQ(plain.height_px, 16);
}

TEST_F(CaptionText, EmptyTextIsNoBitmap) {
  const CaptionBitmap b = font_.Layout("", 24, 900, 2);
  EXPECT_EQ(b.width_px * b.height_px, 0);
  EXPECT_EQ(b.stats.lines, 0);
}

TEST(CaptionFontFile, AMissingFontNamesTheFile) {
  try {
    CaptionFont font("/nonexistent/font.ttf");
    ADD_FAILURE() << "opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/font.ttf"), std::string::npos) << e.what();
  }
}

// A side-by-side frame of odd width has eyes a pixel apart in width: their two captions are
// both kept, not laid out again for every eye of every frame; another text is laid out once.
TEST(CaptionCacheTest, TheTwoEyesOfAnOddSideBySideFrameKeepTheirLayouts) {
  CaptionCache cache;
  for (int frame = 0; frame < 5; ++frame) {
    EXPECT_GT(cache.For("Welcome", 960, 1080).width_px, 0);
    EXPECT_GT(cache.For("Welcome", 961, 1080).width_px, 0);
  }
  EXPECT_EQ(cache.laid_out(), 2U);
  (void)cache.For("Next", 960, 1080);
  EXPECT_EQ(cache.laid_out(), 3U);
  EXPECT_EQ(cache.stats().glyphs, 4);
  (void)cache.For("", 960, 1080);
  EXPECT_EQ(cache.laid_out(), 3U) << "no text, no layout";
  EXPECT_EQ(cache.stats().glyphs, 0);
}

}  // namespace
}  // namespace handshare::render::detail
