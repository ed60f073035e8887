#pragma once
/// @file
/// An 8-bit RGB image and PNG file I/O (libpng).

#include <cstdint>
#include <filesystem>
#include <vector>

namespace handshare::render {

/// An RGB8 image, row-major, row 0 at the top, 3 bytes per pixel, no padding.
struct ImageRgb8 {
  int width_px = 0;
  int height_px = 0;
  std::vector<std::uint8_t> rgb;  ///< size 3 * width_px * height_px.

  ImageRgb8() = default;
  /// A black image of the given size (throws std::invalid_argument on negative sizes).
  ImageRgb8(int width, int height);

  /// Pointer to the 3 bytes of pixel (col, row); unchecked beyond an always-on bounds assert.
  [[nodiscard]] const std::uint8_t* At(int col, int row) const;
  [[nodiscard]] std::uint8_t* At(int col, int row);
};

/// Writes `image` as an 8-bit RGB PNG. Throws std::runtime_error naming `path` and libpng's reason
/// on failure, std::invalid_argument if the image's buffer does not match its size.
void WritePng(const std::filesystem::path& path, const ImageRgb8& image);

/// Reads any PNG (grey, palette, alpha and 16-bit are converted to RGB8; alpha is composited
/// over black). Throws std::runtime_error naming `path` and the reason on failure.
[[nodiscard]] ImageRgb8 ReadPng(const std::filesystem::path& path);

}  // namespace handshare::render
