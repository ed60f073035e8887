#pragma once
/// UTF-8 text as code points: for drawing a caption glyph by glyph, and for checking that a
/// Japanese reading holds only what eSpeak NG's ja voice reads.
#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

namespace handshare::common {

inline constexpr char32_t kReplacementCharacter = 0xFFFD;

/// One code point decoded at byte `at` of `text`, and how many bytes it took (>= 1). An invalid
/// or truncated sequence gives U+FFFD and 1 byte, so decoding resynchronizes on the next byte.
struct CodePointAt {
  char32_t code_point = kReplacementCharacter;
  std::size_t bytes = 1;
};
[[nodiscard]] CodePointAt DecodeOne(std::string_view text, std::size_t at) noexcept;

/// Every code point of `text`, invalid bytes as U+FFFD.
[[nodiscard]] std::vector<char32_t> DecodeUtf8(std::string_view text);

/// What a Japanese reading for eSpeak NG's ja voice may hold: hiragana, katakana with the long
/// vowel mark, ASCII, the ideographic comma, full stop and space. The voice says "Chinese letter" in
/// English for a kanji and spells other signs (the katakana middle dot is read "Japanese letter").
[[nodiscard]] constexpr bool IsKanaReadingChar(char32_t c) noexcept {
  return (c >= 0x20 && c < 0x7F) || (c >= 0x3041 && c <= 0x3096) || (c >= 0x30A1 && c <= 0x30FA) ||
         c == 0x30FC || c == 0x3001 || c == 0x3002 || c == 0x3000;
}

/// The byte offset of the first code point of `text` that a kana reading may not hold, if any.
[[nodiscard]] std::optional<std::size_t> FirstOutsideKanaReading(std::string_view text) noexcept;

}  // namespace handshare::common
