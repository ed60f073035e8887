#include "page_texture.hpp"

#include <algorithm>
#include <cmath>

namespace handshare::render::detail {

namespace {

std::uint8_t Channel(float v) { return static_cast<std::uint8_t>(std::lround(255.0F * std::clamp(v, 0.0F, 1.0F))); }

// The picture into the rectangle [x0, x0 + w) x [y0, y0 + h) of `out`, bilinear.
void Blit(const ImageRgb8& image, int x0, int y0, int w, int h, PageTexture& out) {
  for (int y = 0; y < h; ++y) {
    const double sy = std::clamp((y + 0.5) * image.height_px / h - 0.5, 0.0, image.height_px - 1.0);
    const int iy = std::min(static_cast<int>(sy), std::max(0, image.height_px - 2));
    const double fy = sy - iy;
    for (int x = 0; x < w; ++x) {
      const double sx = std::clamp((x + 0.5) * image.width_px / w - 0.5, 0.0, image.width_px - 1.0);
      const int ix = std::min(static_cast<int>(sx), std::max(0, image.width_px - 2));
      const double fx = sx - ix;
      const int ix1 = std::min(ix + 1, image.width_px - 1);
      const int iy1 = std::min(iy + 1, image.height_px - 1);
      std::uint8_t* dst = out.At(x0 + x, y0 + y);
      for (int c = 0; c < 3; ++c) {
        const double top = (1.0 - fx) * image.At(ix, iy)[c] + fx * image.At(ix1, iy)[c];
        const double bottom = (1.0 - fx) * image.At(ix, iy1)[c] + fx * image.At(ix1, iy1)[c];
        dst[c] = static_cast<std::uint8_t>(std::lround(std::clamp((1.0 - fy) * top + fy * bottom, 0.0, 255.0)));
      }
    }
  }
}

}  // namespace

int PageTextureHeight(const Page& page) {
  const double wide = (page.corners_W[1] - page.corners_W[0]).norm();
  const double high = (page.corners_W[3] - page.corners_W[0]).norm();
  const double aspect = wide > 1e-9 && std::isfinite(high / wide) ? std::clamp(high / wide, 0.25, 4.0) : 1.0;
  return static_cast<int>(std::lround(kPageTextureWidth * aspect));
}

PageTexture ComposePage(CaptionFont* font, const Page& page, int width_px, int height_px) {
  PageTexture out;
  out.width_px = std::max(1, width_px);
  out.height_px = std::max(1, height_px);
  out.rgb.resize(3 * static_cast<std::size_t>(out.width_px) * static_cast<std::size_t>(out.height_px));
  const std::uint8_t paper[3] = {Channel(page.paper.r), Channel(page.paper.g), Channel(page.paper.b)};
  for (std::size_t p = 0; p < out.rgb.size(); p += 3) std::copy_n(paper, 3, out.rgb.data() + p);

  const int margin = std::max(2, out.width_px / 16);
  const int inner_w = std::max(1, out.width_px - 2 * margin);
  int top = margin;  // the first row not yet used
  if (page.image && page.image->width_px > 0 && page.image->height_px > 0) {
    const int room_h = std::max(1, (page.text.empty() ? out.height_px - 2 * margin : out.height_px * 3 / 5 - margin));
    // Fitted: as wide as the room allows, unless that makes it too high.
    double scale = static_cast<double>(inner_w) / page.image->width_px;
    scale = std::min(scale, static_cast<double>(room_h) / page.image->height_px);
    const int w = std::max(1, static_cast<int>(std::lround(page.image->width_px * scale)));
    const int h = std::max(1, static_cast<int>(std::lround(page.image->height_px * scale)));
    Blit(*page.image, margin + (inner_w - w) / 2, top, std::min(w, inner_w), std::min(h, out.height_px - top), out);
    top += h + margin / 2;
  }
  if (font != nullptr && !page.text.empty() && top < out.height_px - margin) {
    const int pixel_size = std::max(10, out.width_px / 16);
    const int line_px = pixel_size * 5 / 4;  // about the font's line height
    const int room = out.height_px - margin - top;
    CaptionBitmap text = font->Layout(page.text, pixel_size, inner_w, std::max(1, room / line_px));
    if (text.height_px > room && text.stats.lines > 0) {
      // The font's lines are taller than guessed: lay it out again in as many as fit.
      const int font_line_px = std::max(1, text.height_px / text.stats.lines);
      text = font->Layout(page.text, pixel_size, inner_w, std::max(1, room / font_line_px));
    }
    out.text = text.stats;
    const float ink[3] = {page.ink.r, page.ink.g, page.ink.b};
    const int rows = std::min(text.height_px, room);
    const int cols = std::min(text.width_px, inner_w);
    for (int y = 0; y < rows; ++y) {
      for (int x = 0; x < cols; ++x) {
        const double a = text.At(x, y) / 255.0;
        if (a <= 0.0) continue;
        std::uint8_t* dst = out.At(margin + x, top + y);
        for (int c = 0; c < 3; ++c) {
          dst[c] = static_cast<std::uint8_t>(std::lround((1.0 - a) * dst[c] + a * 255.0 * std::clamp(ink[c], 0.0F, 1.0F)));
        }
      }
    }
  }
  return out;
}

PageCache::PageCache(std::filesystem::path font_file) : font_file_(std::move(font_file)) {}
PageCache::~PageCache() = default;

const PageTexture& PageCache::For(const Page& page) {
  ++clock_;
  const int height_px = PageTextureHeight(page);
  const auto same = [](const Rgb& a, const Rgb& b) { return a.r == b.r && a.g == b.g && a.b == b.b; };
  for (Entry& e : entries_) {
    if (e.text == page.text && e.image == page.image && e.height_px == height_px && same(e.paper, page.paper) &&
        same(e.ink, page.ink)) {
      e.used = clock_;
      return e.texture;
    }
  }
  if (!font_ && !page.text.empty()) font_ = std::make_unique<CaptionFont>(font_file_);
  Entry fresh{page.text, page.image, page.paper, page.ink, height_px, clock_, {}};
  fresh.texture = ComposePage(font_.get(), page, kPageTextureWidth, height_px);  // no text: no font needed
  fresh.texture.serial = ++composed_;
  if (entries_.size() < kEntries) {
    fresh.texture.slot = entries_.size();
    entries_.push_back(std::move(fresh));
    return entries_.back().texture;
  }
  auto oldest = std::min_element(entries_.begin(), entries_.end(), [](const Entry& a, const Entry& b) { return a.used < b.used; });
  fresh.texture.slot = static_cast<std::size_t>(oldest - entries_.begin());
  *oldest = std::move(fresh);
  return oldest->texture;
}

}  // namespace handshare::render::detail
