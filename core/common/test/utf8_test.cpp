#include "handshare/common/utf8.hpp"

#include <gtest/gtest.h>

namespace handshare::common {
namespace {

TEST(Utf8, DecodesEveryLengthAndReplacesInvalidBytes) {
  // "a", e-acute (2 bytes), CJK "sun" (3 bytes), an emoji (4 bytes), a tab.
  EXPECT_EQ(DecodeUtf8("a\xC3\xA9\xE6\x97\xA5\xF0\x9F\x98\x80\t"),
            (std::vector<char32_t>{U'a', 0xE9, 0x65E5, 0x1F600, U'\t'}));
  // A stray continuation byte and a truncated sequence each become U+FFFD, one per byte.
  EXPECT_EQ(DecodeUtf8("\x80z\xE6\x97"), (std::vector<char32_t>{0xFFFD, U'z', 0xFFFD, 0xFFFD}));
  EXPECT_TRUE(DecodeUtf8("").empty());
}

TEST(Utf8, FindsWhatAKanaReadingMayNotHold) {
  EXPECT_FALSE(FirstOutsideKanaReading("kore wa tsuki desu!").has_value());
  EXPECT_FALSE(FirstOutsideKanaReading("これは つきです。 ジュウリョク、38パーセント").has_value());
  EXPECT_EQ(FirstOutsideKanaReading("これは月です"), 9U);  // three kana of 3 bytes, then a kanji
  EXPECT_EQ(FirstOutsideKanaReading("ab\xE6\x97\xA5"), 2U);
  EXPECT_EQ(FirstOutsideKanaReading("ダフニア・ロンギスピナ"), 12U);  // the middle dot
  EXPECT_EQ(FirstOutsideKanaReading("あ\x80"), 3U);                   // an invalid byte
  EXPECT_EQ(FirstOutsideKanaReading("tab\there"), 3U);                // a control character
  EXPECT_FALSE(IsKanaReadingChar(U'\u4E00'));
  EXPECT_TRUE(IsKanaReadingChar(U'\u3042'));  // hiragana a
  EXPECT_TRUE(IsKanaReadingChar(U'\u30A2'));  // katakana a
  EXPECT_TRUE(IsKanaReadingChar(U'\u30FC'));  // long vowel mark
}

}  // namespace
}  // namespace handshare::common
