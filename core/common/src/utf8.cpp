#include "handshare/common/utf8.hpp"

namespace handshare::common {

CodePointAt DecodeOne(std::string_view text, std::size_t at) noexcept {
  const auto lead = static_cast<unsigned char>(text[at]);
  std::size_t extra = 0;
  char32_t cp = 0;
  if (lead < 0x80U) return {lead, 1};
  if ((lead & 0xE0U) == 0xC0U) {
    extra = 1;
    cp = lead & 0x1FU;
  } else if ((lead & 0xF0U) == 0xE0U) {
    extra = 2;
    cp = lead & 0x0FU;
  } else if ((lead & 0xF8U) == 0xF0U) {
    extra = 3;
    cp = lead & 0x07U;
  } else {
    return {};
  }
  if (at + extra >= text.size()) return {};
  for (std::size_t k = 1; k <= extra; ++k) {
    const auto byte = static_cast<unsigned char>(text[at + k]);
    if ((byte & 0xC0U) != 0x80U) return {};
    cp = (cp << 6U) | (byte & 0x3FU);
  }
  return {cp, extra + 1};
}

std::vector<char32_t> DecodeUtf8(std::string_view text) {
  std::vector<char32_t> out;
  out.reserve(text.size());
  for (std::size_t i = 0; i < text.size();) {
    const CodePointAt one = DecodeOne(text, i);
    out.push_back(one.code_point);
    i += one.bytes;
  }
  return out;
}

std::optional<std::size_t> FirstOutsideKanaReading(std::string_view text) noexcept {
  for (std::size_t i = 0; i < text.size();) {
    const CodePointAt one = DecodeOne(text, i);
    if (!IsKanaReadingChar(one.code_point)) return i;
    i += one.bytes;
  }
  return std::nullopt;
}

}  // namespace handshare::common
