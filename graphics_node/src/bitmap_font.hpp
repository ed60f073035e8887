#pragma once
// A built-in 5x7 bitmap font for printable ASCII (drawn for this project), and a UTF-8 splitter
// that marks everything else as "no glyph" so the caption can draw a box in its place.

#include <cstdint>
#include <string_view>
#include <vector>

namespace handshare::render::detail {

inline constexpr int kGlyphWidth = 5;
inline constexpr int kGlyphHeight = 7;

/// True if pixel (col, row) of the glyph for `c` is set; row 0 is the top. `c` must be printable
/// ASCII (0x20..0x7E); anything else has no glyph and returns false.
[[nodiscard]] bool GlyphPixel(char32_t c, int col, int row) noexcept;

/// True if `c` has a glyph in the built-in font.
[[nodiscard]] constexpr bool HasGlyph(char32_t c) noexcept { return c >= 0x20 && c <= 0x7E; }

/// Splits UTF-8 text into code points; an invalid byte becomes U+FFFD. Tabs become spaces.
[[nodiscard]] std::vector<char32_t> DecodeUtf8(std::string_view text);

}  // namespace handshare::render::detail
