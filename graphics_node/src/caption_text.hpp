#pragma once
// The caption's text, laid out with FreeType in a real font: UTF-8 paragraphs wrapped to a
// width (at spaces, and between any two Japanese characters), antialiased into a coverage
// bitmap that the scene drawer blends over the frame.

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <tuple>
#include <vector>

#include "handshare/render/scene_view.hpp"

namespace handshare::render::detail {

/// A laid-out caption: coverage 0..255 per pixel, row 0 at the top.
struct CaptionBitmap {
  int width_px = 0;
  int height_px = 0;
  std::vector<std::uint8_t> coverage;
  CaptionStats stats;

  [[nodiscard]] std::uint8_t At(int x, int y) const {
    return coverage[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_px) + static_cast<std::size_t>(x)];
  }
};

/// One font face at one pixel size at a time. Not thread-safe; not real-time safe.
class CaptionFont {
 public:
  /// Opens `font_file` (TrueType/OpenType; a collection's first face). Throws
  /// std::runtime_error naming the file if FreeType cannot open it.
  explicit CaptionFont(const std::filesystem::path& font_file);
  ~CaptionFont();
  CaptionFont(const CaptionFont&) = delete;
  CaptionFont& operator=(const CaptionFont&) = delete;

  /// True if the font has a glyph for `c`.
  [[nodiscard]] bool HasGlyph(char32_t c) const;

  /// Lays `text` out at `pixel_size` (the em height) in lines of at most `max_width_px`, at most
  /// `max_lines` of them ('\n' starts a new paragraph). A character the font lacks is drawn as a
  /// hollow box and counted in stats.missing_glyphs; text beyond the last line is cut and the
  /// last line ends in an ellipsis. The bitmap is as wide as the longest line.
  [[nodiscard]] CaptionBitmap Layout(std::string_view text, int pixel_size, int max_width_px, int max_lines);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The font captions are drawn in (the build's configured CJK font, fonts-ipafont-gothic).
[[nodiscard]] std::filesystem::path DefaultCaptionFont();

/// The caption of the frames a renderer draws: the font, opened at the first caption, and the
/// last two layouts, kept while the text and the size stay the same (a caption changes with the
/// board, every few seconds at most; a frame is drawn 60 times a second). Two, because the eyes
/// of a side-by-side frame of odd width are a pixel apart in width: one layout would be made
/// again for every eye of every frame.
class CaptionCache {
 public:
  explicit CaptionCache(std::filesystem::path font_file = DefaultCaptionFont());
  ~CaptionCache();
  CaptionCache(const CaptionCache&) = delete;
  CaptionCache& operator=(const CaptionCache&) = delete;

  /// The caption of `text` for a viewport of width_px x height_px: the em height is about 1/30
  /// of the height (at least 12 px), lines are as wide as the viewport less a margin, and they
  /// take at most a third of its height.
  const CaptionBitmap& For(std::string_view text, int width_px, int height_px);

  /// The last caption's statistics.
  [[nodiscard]] const CaptionStats& stats() const { return last_->bitmap.stats; }
  /// How many layouts were made so far.
  [[nodiscard]] std::uint64_t laid_out() const { return laid_out_; }

 private:
  struct Slot {
    std::string text;
    int width_px = -1;
    int height_px = -1;
    CaptionBitmap bitmap;
    std::uint64_t used = 0;
  };
  std::filesystem::path font_file_;
  std::unique_ptr<CaptionFont> font_;
  std::array<Slot, 2> slots_;
  const Slot* last_ = &slots_[0];
  std::uint64_t clock_ = 0;
  std::uint64_t laid_out_ = 0;
};

/// The labels' layouts, kept while their text and size stay the same (labels change with the
/// world; a frame draws each up to 60 times a second). Keeps at most kEntries layouts; beyond
/// that it starts over. Not thread-safe.
class LabelCache {
 public:
  static constexpr std::size_t kEntries = 64;
  /// Labels: em height 1/40 of the viewport's, at most two lines. Other blocks of text (the
  /// overlay) pass their own.
  explicit LabelCache(std::filesystem::path font_file = DefaultCaptionFont(), int em_divisor = 40, int max_lines = 2);
  ~LabelCache();
  LabelCache(const LabelCache&) = delete;
  LabelCache& operator=(const LabelCache&) = delete;

  /// `text` laid out for a viewport `height_px` high: em height 1/em_divisor of it (at least
  /// 12 px), at most max_lines lines of at most `max_width_px`.
  const CaptionBitmap& For(const std::string& text, int height_px, int max_width_px);
  /// How many layouts were made so far.
  [[nodiscard]] std::uint64_t laid_out() const { return laid_out_; }

 private:
  std::filesystem::path font_file_;
  int em_divisor_;
  int max_lines_;
  std::unique_ptr<CaptionFont> font_;
  std::map<std::tuple<std::string, int, int>, CaptionBitmap> layouts_;
  std::uint64_t laid_out_ = 0;
};

}  // namespace handshare::render::detail
