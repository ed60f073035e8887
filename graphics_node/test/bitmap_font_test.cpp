#include "bitmap_font.hpp"

#include <gtest/gtest.h>

#include <set>
#include <string>

namespace handshare::render::detail {
namespace {

std::string GlyphBits(char32_t c) {
  std::string bits;
  for (int row = 0; row < kGlyphHeight; ++row) {
    for (int col = 0; col < kGlyphWidth; ++col) bits += GlyphPixel(c, col, row) ? '#' : '.';
  }
  return bits;
}

TEST(RenderFont, EveryPrintableCharacterHasADistinctGlyph) {
  std::set<std::string> seen;
  for (char32_t c = 0x21; c <= 0x7E; ++c) {
    const std::string bits = GlyphBits(c);
    EXPECT_NE(bits.find('#'), std::string::npos) << "empty glyph for " << static_cast<char>(c);
    EXPECT_TRUE(seen.insert(bits).second) << "duplicate glyph for " << static_cast<char>(c);
  }
  EXPECT_EQ(GlyphBits(U' ').find('#'), std::string::npos);
}

TEST(RenderFont, GlyphsAreUprightAndNotMirrored) {
  // 'L' has its bar at the bottom row and its stem in the left column.
  for (int col = 0; col < kGlyphWidth; ++col) EXPECT_TRUE(GlyphPixel(U'L', col, kGlyphHeight - 1));
  for (int row = 0; row < kGlyphHeight; ++row) EXPECT_TRUE(GlyphPixel(U'L', 0, row));
  EXPECT_FALSE(GlyphPixel(U'L', kGlyphWidth - 1, 0));
  // 'T' has its bar at the top.
  for (int col = 0; col < kGlyphWidth; ++col) EXPECT_TRUE(GlyphPixel(U'T', col, 0));
  EXPECT_FALSE(GlyphPixel(U'T', 0, kGlyphHeight - 1));
}

TEST(RenderFont, NonAsciiAndOutOfRangeHaveNoGlyph) {
  EXPECT_FALSE(HasGlyph(U'\n'));
  EXPECT_FALSE(HasGlyph(0x7F));
  EXPECT_FALSE(HasGlyph(U'\u65E5'));
  EXPECT_FALSE(GlyphPixel(U'\u65E5', 2, 3));
  EXPECT_FALSE(GlyphPixel(U'A', -1, 0));
  EXPECT_FALSE(GlyphPixel(U'A', 0, kGlyphHeight));
}

TEST(RenderFont, DecodesUtf8AndReplacesInvalidBytes) {
  // "a", e-acute (2 bytes), CJK "sun" (3 bytes), an emoji (4 bytes), a tab.
  const std::vector<char32_t> decoded = DecodeUtf8("a\xC3\xA9\xE6\x97\xA5\xF0\x9F\x98\x80\t");
  EXPECT_EQ(decoded, (std::vector<char32_t>{U'a', 0xE9, 0x65E5, 0x1F600, U' '}));
  // A stray continuation byte and a truncated sequence each become U+FFFD.
  EXPECT_EQ(DecodeUtf8("\x80z\xE6\x97"), (std::vector<char32_t>{0xFFFD, U'z', 0xFFFD, 0xFFFD}));
  EXPECT_TRUE(DecodeUtf8("").empty());
}

}  // namespace
}  // namespace handshare::render::detail
