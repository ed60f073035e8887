#include "handshare/render/image.hpp"

#include <png.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace handshare::render {

ImageRgb8::ImageRgb8(int width, int height) : width_px(width), height_px(height) {
  if (width < 0 || height < 0) {
    throw std::invalid_argument("render::ImageRgb8: negative size " + std::to_string(width) +
                                " x " + std::to_string(height));
  }
  rgb.assign(static_cast<std::size_t>(3) * static_cast<std::size_t>(width) *
                 static_cast<std::size_t>(height),
             0);
}

namespace {

std::size_t Offset(const ImageRgb8& image, int col, int row) {
  if (col < 0 || col >= image.width_px || row < 0 || row >= image.height_px) {
    // A caller's bug, not a runtime condition: stop loudly.
    std::fprintf(stderr, "render::ImageRgb8::At(%d, %d) outside %d x %d\n", col, row,
                 image.width_px, image.height_px);
    std::abort();
  }
  return 3 * (static_cast<std::size_t>(row) * static_cast<std::size_t>(image.width_px) +
              static_cast<std::size_t>(col));
}

}  // namespace

const std::uint8_t* ImageRgb8::At(int col, int row) const { return rgb.data() + Offset(*this, col, row); }

std::uint8_t* ImageRgb8::At(int col, int row) { return rgb.data() + Offset(*this, col, row); }

void WritePng(const std::filesystem::path& path, const ImageRgb8& image) {
  const std::size_t expected =
      3 * static_cast<std::size_t>(image.width_px) * static_cast<std::size_t>(image.height_px);
  if (image.width_px <= 0 || image.height_px <= 0 || image.rgb.size() != expected) {
    throw std::invalid_argument("WritePng(" + path.string() + "): image is " +
                                std::to_string(image.width_px) + " x " +
                                std::to_string(image.height_px) + " px with " +
                                std::to_string(image.rgb.size()) + " bytes (needs " +
                                std::to_string(expected) + ", non-empty)");
  }
  // libpng's simplified API reports errors in image.message instead of longjmp-ing.
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  png.width = static_cast<png_uint_32>(image.width_px);
  png.height = static_cast<png_uint_32>(image.height_px);
  png.format = PNG_FORMAT_RGB;
  const int ok = png_image_write_to_file(&png, path.c_str(), 0, image.rgb.data(),
                                         3 * image.width_px, nullptr);
  if (ok == 0) {
    const std::string reason = png.message;
    png_image_free(&png);
    throw std::runtime_error("WritePng(" + path.string() + "): " + reason);
  }
}

ImageRgb8 ReadPng(const std::filesystem::path& path) {
  png_image png{};
  png.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&png, path.c_str()) == 0) {
    const std::string reason = png.message;
    png_image_free(&png);
    throw std::runtime_error("ReadPng(" + path.string() + "): " + reason);
  }
  png.format = PNG_FORMAT_RGB;
  ImageRgb8 image(static_cast<int>(png.width), static_cast<int>(png.height));
  const png_color black{0, 0, 0};
  if (png_image_finish_read(&png, &black, image.rgb.data(), 3 * image.width_px, nullptr) == 0) {
    const std::string reason = png.message;
    png_image_free(&png);
    throw std::runtime_error("ReadPng(" + path.string() + "): " + reason);
  }
  return image;
}

}  // namespace handshare::render
