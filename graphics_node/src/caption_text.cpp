#include "caption_text.hpp"

#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <stdexcept>

#include "handshare/common/utf8.hpp"

namespace handshare::render::detail {

namespace {

// Japanese and Chinese text has no spaces: a line may break before or after any such character.
bool IsCjk(char32_t c) { return c >= 0x2E80 && c <= 0x9FFF; }
// ...except before closing punctuation, which stays on the line it closes (kinsoku).
bool NoBreakBefore(char32_t c) {
  return c == U'、' || c == U'。' || c == U'」' || c == U'）' || c == U'ー' || c == U')' || c == U',' || c == U'.' ||
         c == U'!' || c == U'?' || c == U'%';
}

std::string FreeTypeError(FT_Error error) {
  const char* s = FT_Error_String(error);
  return s != nullptr ? s : "FreeType error " + std::to_string(error);
}

}  // namespace

struct CaptionFont::Impl {
  FT_Library library = nullptr;
  FT_Face face = nullptr;
  int pixel_size = 0;

  // One glyph at the current size: its coverage, where it sits and how far the pen moves.
  struct Glyph {
    int left = 0, top = 0, width = 0, rows = 0, advance = 0;
    bool missing = false;
    std::vector<std::uint8_t> coverage;
  };

  void SetSize(int size) {
    if (size == pixel_size) return;
    if (const FT_Error e = FT_Set_Pixel_Sizes(face, 0, static_cast<FT_UInt>(size)); e != 0) {
      throw std::runtime_error("caption font: cannot set size " + std::to_string(size) + " px: " + FreeTypeError(e));
    }
    pixel_size = size;
  }

  Glyph Render(char32_t c) const {
    Glyph g;
    const FT_UInt index = FT_Get_Char_Index(face, c);
    if (index == 0) {
      // A hollow box an em wide, so a missing character is seen, not silently dropped.
      g.missing = true;
      g.width = std::max(3, pixel_size * 3 / 5);
      g.rows = std::max(3, pixel_size * 7 / 10);
      g.left = std::max(1, pixel_size / 10);
      g.top = g.rows;
      g.advance = g.width + 2 * g.left;
      g.coverage.assign(static_cast<std::size_t>(g.width * g.rows), 0);
      for (int y = 0; y < g.rows; ++y) {
        for (int x = 0; x < g.width; ++x) {
          if (y == 0 || y == g.rows - 1 || x == 0 || x == g.width - 1) g.coverage[static_cast<std::size_t>(y * g.width + x)] = 255;
        }
      }
      return g;
    }
    if (const FT_Error e = FT_Load_Glyph(face, index, FT_LOAD_RENDER); e != 0) {
      throw std::runtime_error("caption font: cannot render U+" + std::to_string(static_cast<unsigned>(c)) + ": " +
                               FreeTypeError(e));
    }
    const FT_GlyphSlot slot = face->glyph;
    const FT_Bitmap& bm = slot->bitmap;
    g.left = slot->bitmap_left;
    g.top = slot->bitmap_top;
    g.width = static_cast<int>(bm.width);
    g.rows = static_cast<int>(bm.rows);
    g.advance = static_cast<int>(slot->advance.x >> 6);
    g.coverage.resize(static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.rows));
    for (int y = 0; y < g.rows; ++y) {
      for (int x = 0; x < g.width; ++x) {
        g.coverage[static_cast<std::size_t>(y * g.width + x)] = bm.buffer[y * bm.pitch + x];
      }
    }
    return g;
  }
};

CaptionFont::CaptionFont(const std::filesystem::path& font_file) : impl_(std::make_unique<Impl>()) {
  if (const FT_Error e = FT_Init_FreeType(&impl_->library); e != 0) {
    throw std::runtime_error("caption font: FreeType does not start: " + FreeTypeError(e));
  }
  if (const FT_Error e = FT_New_Face(impl_->library, font_file.c_str(), 0, &impl_->face); e != 0) {
    FT_Done_FreeType(impl_->library);
    throw std::runtime_error("caption font '" + font_file.string() + "' cannot be opened: " + FreeTypeError(e) +
                             " (Debian: fonts-ipafont-gothic)");
  }
}

CaptionFont::~CaptionFont() {
  if (impl_->face != nullptr) FT_Done_Face(impl_->face);
  if (impl_->library != nullptr) FT_Done_FreeType(impl_->library);
}

bool CaptionFont::HasGlyph(char32_t c) const { return FT_Get_Char_Index(impl_->face, c) != 0; }

CaptionBitmap CaptionFont::Layout(std::string_view text, int pixel_size, int max_width_px, int max_lines) {
  CaptionBitmap out;
  out.stats.pixel_size = pixel_size;
  if (text.empty() || max_lines <= 0 || max_width_px <= 0) return out;
  impl_->SetSize(std::max(1, pixel_size));

  std::vector<char32_t> cps = common::DecodeUtf8(text);
  for (char32_t& c : cps) {
    if (c == U'\t') c = U' ';
  }

  // Greedy line filling over break opportunities; each line is a range of code points.
  struct Line {
    std::size_t begin = 0, end = 0;
    bool ellipsis = false;
  };
  std::vector<Line> lines;
  std::vector<int> advance(cps.size(), 0);
  for (std::size_t i = 0; i < cps.size(); ++i) {
    if (cps[i] == U'\n') continue;
    if (cps[i] < 0x20 || cps[i] == 0x7F) cps[i] = U' ';
    const FT_UInt index = FT_Get_Char_Index(impl_->face, cps[i]);
    if (index == 0) {
      advance[i] = std::max(3, pixel_size * 3 / 5) + 2 * std::max(1, pixel_size / 10);
    } else if (FT_Load_Glyph(impl_->face, index, FT_LOAD_DEFAULT) == 0) {
      advance[i] = static_cast<int>(impl_->face->glyph->advance.x >> 6);
    }
  }
  std::size_t i = 0;
  while (i < cps.size()) {
    if (cps[i] == U'\n') {  // an empty paragraph is an empty line
      lines.push_back({i, i});
      ++i;
      continue;
    }
    const std::size_t begin = i;
    int width = 0;
    std::size_t last_break = begin;  // a line may end before this index (exclusive end)
    std::size_t end = begin;
    while (end < cps.size() && cps[end] != U'\n') {
      if (width + advance[end] > max_width_px && end > begin) break;
      width += advance[end];
      ++end;
      const bool space = end < cps.size() && cps[end] == U' ';
      const bool cjk = end < cps.size() && (IsCjk(cps[end]) || IsCjk(cps[end - 1])) && !NoBreakBefore(cps[end]);
      if (space || cjk || end == cps.size() || cps[end] == U'\n') last_break = end;
    }
    if (end < cps.size() && cps[end] != U'\n' && last_break > begin) end = last_break;  // wrap at a break
    lines.push_back({begin, end});
    i = end;
    while (i < cps.size() && cps[i] == U' ') ++i;  // the spaces at a wrap vanish
    if (i < cps.size() && cps[i] == U'\n') ++i;  // the paragraph's end
  }
  if (static_cast<int>(lines.size()) > max_lines) {
    lines.resize(static_cast<std::size_t>(max_lines));
    lines.back().ellipsis = true;
    out.stats.cut = true;
  }

  // Draw each line's glyphs on a common baseline, on a canvas a line taller above and below:
  // a glyph may reach past its line (IPA Gothic's line height is exactly its em, and a
  // descender or a ring goes beyond it), and the first and last lines' were cut there.
  const FT_Size_Metrics& m = impl_->face->size->metrics;
  const int ascender = static_cast<int>(m.ascender >> 6);
  const int line_height = std::max(1, static_cast<int>(m.height >> 6));
  const int lines_px = line_height * static_cast<int>(lines.size());
  const int room_px = line_height;
  out.width_px = max_width_px;
  out.height_px = lines_px + 2 * room_px;
  out.coverage.assign(static_cast<std::size_t>(out.width_px) * static_cast<std::size_t>(out.height_px), 0);
  int widest = 0;
  const auto blit = [&](const Impl::Glyph& g, int pen_x, int baseline) {
    for (int y = 0; y < g.rows; ++y) {
      const int py = baseline - g.top + y;
      if (py < 0 || py >= out.height_px) continue;
      for (int x = 0; x < g.width; ++x) {
        const int px = pen_x + g.left + x;
        if (px < 0 || px >= out.width_px) continue;
        std::uint8_t& dst = out.coverage[static_cast<std::size_t>(py) * static_cast<std::size_t>(out.width_px) +
                                         static_cast<std::size_t>(px)];
        dst = std::max(dst, g.coverage[static_cast<std::size_t>(y * g.width + x)]);
      }
    }
  };
  const Impl::Glyph dots = impl_->Render(U'…');
  for (std::size_t l = 0; l < lines.size(); ++l) {
    const int baseline = room_px + static_cast<int>(l) * line_height + ascender;
    int pen = 0;
    std::size_t end = lines[l].end;
    if (lines[l].ellipsis) {  // make room for the ellipsis
      int width = 0;
      for (std::size_t k = lines[l].begin; k < end; ++k) width += advance[k];
      while (end > lines[l].begin && width + dots.advance > max_width_px) width -= advance[--end];
    }
    for (std::size_t k = lines[l].begin; k < end; ++k) {
      const Impl::Glyph g = impl_->Render(cps[k]);
      blit(g, pen, baseline);
      pen += g.advance;
      if (g.missing) {
        ++out.stats.missing_glyphs;
      } else if (cps[k] != U' ' && cps[k] != 0x3000) {
        ++out.stats.glyphs;
      }
    }
    if (lines[l].ellipsis) {
      blit(dots, pen, baseline);
      pen += dots.advance;
    }
    widest = std::max(widest, std::min(pen, max_width_px));
  }
  out.stats.lines = static_cast<int>(lines.size());
  // Keep the lines' rows and whatever ink reaches beyond them.
  const auto inked = [&](int y) {
    const auto row = out.coverage.begin() + static_cast<std::ptrdiff_t>(y) * out.width_px;
    return std::any_of(row, row + out.width_px, [](std::uint8_t c) { return c != 0; });
  };
  int first = 0;  // rows [first, last)
  while (first < room_px && !inked(first)) ++first;
  int last = out.height_px;
  while (last > room_px + lines_px && !inked(last - 1)) --last;
  if (first > 0 || last < out.height_px) {
    out.coverage.erase(out.coverage.begin() + static_cast<std::ptrdiff_t>(last) * out.width_px, out.coverage.end());
    out.coverage.erase(out.coverage.begin(), out.coverage.begin() + static_cast<std::ptrdiff_t>(first) * out.width_px);
    out.height_px = last - first;
  }
  // Trim to the widest line.
  if (widest < out.width_px) {
    std::vector<std::uint8_t> trimmed(static_cast<std::size_t>(widest) * static_cast<std::size_t>(out.height_px));
    for (int y = 0; y < out.height_px; ++y) {
      std::copy_n(out.coverage.begin() + static_cast<std::ptrdiff_t>(y) * out.width_px, widest,
                  trimmed.begin() + static_cast<std::ptrdiff_t>(y) * widest);
    }
    out.coverage = std::move(trimmed);
    out.width_px = widest;
  }
  return out;
}

std::filesystem::path DefaultCaptionFont() { return HANDSHARE_CAPTION_FONT; }

CaptionCache::CaptionCache(std::filesystem::path font_file) : font_file_(std::move(font_file)) {}
CaptionCache::~CaptionCache() = default;

const CaptionBitmap& CaptionCache::For(std::string_view text, int width_px, int height_px) {
  ++clock_;
  for (Slot& s : slots_) {
    if (s.used != 0 && text == s.text && width_px == s.width_px && height_px == s.height_px) {
      s.used = clock_;
      last_ = &s;
      return s.bitmap;
    }
  }
  Slot& s = slots_[0].used <= slots_[1].used ? slots_[0] : slots_[1];  // the one used longest ago
  s.text = text;
  s.width_px = width_px;
  s.height_px = height_px;
  s.used = clock_;
  last_ = &s;
  if (text.empty()) {  // no caption: the font is not even opened
    s.bitmap = CaptionBitmap{};
    return s.bitmap;
  }
  if (!font_) font_ = std::make_unique<CaptionFont>(font_file_);
  ++laid_out_;
  const int pixel_size = std::max(12, height_px / 30);
  const int margin_px = pixel_size;
  const int line_px = pixel_size * 5 / 4;  // about the font's line height
  const int max_lines = std::max(1, (height_px / 3) / line_px);
  s.bitmap = font_->Layout(text, pixel_size, std::max(1, width_px - 2 * margin_px), max_lines);
  return s.bitmap;
}

LabelCache::LabelCache(std::filesystem::path font_file, int em_divisor, int max_lines)
    : font_file_(std::move(font_file)), em_divisor_(std::max(1, em_divisor)), max_lines_(std::max(1, max_lines)) {}
LabelCache::~LabelCache() = default;

const CaptionBitmap& LabelCache::For(const std::string& text, int height_px, int max_width_px) {
  const int pixel_size = std::max(12, height_px / em_divisor_);
  const auto key = std::make_tuple(text, pixel_size, max_width_px);
  if (const auto it = layouts_.find(key); it != layouts_.end()) return it->second;
  if (layouts_.size() >= kEntries) layouts_.clear();
  if (!font_) font_ = std::make_unique<CaptionFont>(font_file_);
  ++laid_out_;
  return layouts_.emplace(key, font_->Layout(text, pixel_size, std::max(1, max_width_px), max_lines_)).first->second;
}

}  // namespace handshare::render::detail
