#pragma once
/// @file
/// Headless software rendering (Mesa OSMesa, llvmpipe) of a SceneView into an RGB8 image.

#include <cstdint>
#include <memory>

#include "handshare/render/image.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::render {

/// Renders scenes without any display. Not real-time safe (allocates, software rasterizer).
/// One instance must be used by one thread at a time; separate instances may render on separate
/// threads. The OpenGL context is created in the constructor and made current inside Render().
class OffscreenRenderer {
 public:
  /// Creates the OSMesa context; throws std::runtime_error if Mesa cannot create one.
  OffscreenRenderer();
  ~OffscreenRenderer();
  OffscreenRenderer(const OffscreenRenderer&) = delete;
  OffscreenRenderer& operator=(const OffscreenRenderer&) = delete;
  OffscreenRenderer(OffscreenRenderer&&) noexcept;
  OffscreenRenderer& operator=(OffscreenRenderer&&) noexcept;

  /// Draws `scene` seen by `camera`.
  /// @returns kMono, kAnaglyph: camera.width_px x camera.height_px;
  ///          kSideBySide: (2 * camera.width_px) x camera.height_px, left eye on the left.
  /// Throws std::invalid_argument for an invalid camera or mesh (bad index, normal count),
  /// std::runtime_error if OpenGL fails.
  [[nodiscard]] ImageRgb8 Render(const SceneView& scene, const Camera& camera,
                                 StereoMode mode = StereoMode::kMono);

  /// What the caption of the last rendered frame held (zeros without a caption).
  [[nodiscard]] const CaptionStats& last_caption() const;

  /// How many page textures were uploaded so far: a page is uploaded when its content first
  /// shows (or shows again after 8 others), not every frame.
  [[nodiscard]] std::uint64_t page_uploads() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handshare::render
