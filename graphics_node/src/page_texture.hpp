#pragma once
// A page of the scene (render::Page) as the texture the scene drawer puts on its quad: paper,
// the picture fitted at the top, the text below it laid out in the caption font.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "caption_text.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::render::detail {

/// A composed page: RGB8, row 0 at the page's top edge, 3 bytes per pixel, no padding.
struct PageTexture {
  int width_px = 0;
  int height_px = 0;
  std::vector<std::uint8_t> rgb;
  CaptionStats text;  ///< how the page's text was laid out
  std::uint64_t serial = 0;  ///< PageCache: which composition this is (1, 2, ...; never reused)
  std::size_t slot = 0;      ///< PageCache: where it is kept (0 .. kEntries - 1) while it is kept

  [[nodiscard]] const std::uint8_t* At(int x, int y) const { return rgb.data() + Offset(x, y); }
  [[nodiscard]] std::uint8_t* At(int x, int y) { return rgb.data() + Offset(x, y); }

 private:
  [[nodiscard]] std::size_t Offset(int x, int y) const {
    return 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_px) + static_cast<std::size_t>(x));
  }
};

/// Texture width of every page [px]; the height follows the page's aspect.
inline constexpr int kPageTextureWidth = 256;

/// The texture height for `page` at kPageTextureWidth: its aspect (left edge over bottom edge),
/// clamped to [1/4, 4]; a degenerate quad is square.
[[nodiscard]] int PageTextureHeight(const Page& page);

/// Paper, then the picture (fitted into the page's width less the margins, above the text, and
/// into at most 60% of the height when there is text), then the text in `font` (about 1/16 of
/// the width high), wrapped and cut to the room left. `font` may be null for a page without text.
[[nodiscard]] PageTexture ComposePage(CaptionFont* font, const Page& page, int width_px, int height_px);

/// The textures of the pages a renderer draws, kept while a page shows the same content (a page
/// turns a few times a minute; a frame is drawn up to 60 times a second). Keeps at most
/// kEntries, dropping the one drawn longest ago. Not thread-safe.
class PageCache {
 public:
  static constexpr std::size_t kEntries = 8;
  explicit PageCache(std::filesystem::path font_file = DefaultCaptionFont());
  ~PageCache();
  PageCache(const PageCache&) = delete;
  PageCache& operator=(const PageCache&) = delete;

  /// The texture of `page` (composed now, or kept from an earlier frame).
  const PageTexture& For(const Page& page);

  /// How many textures were composed so far (a page drawn again is not composed again).
  [[nodiscard]] std::uint64_t composed() const { return composed_; }

 private:
  struct Entry {
    std::string text;
    std::shared_ptr<const ImageRgb8> image;  // held: its address stays its identity
    Rgb paper;
    Rgb ink;
    int height_px = 0;
    std::uint64_t used = 0;
    PageTexture texture;
  };
  std::filesystem::path font_file_;
  std::unique_ptr<CaptionFont> font_;
  std::vector<Entry> entries_;
  std::uint64_t clock_ = 0;
  std::uint64_t composed_ = 0;
};

}  // namespace handshare::render::detail
