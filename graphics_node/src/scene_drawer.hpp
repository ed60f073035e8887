#pragma once
// Draws a SceneView with fixed-function OpenGL through a GlApi table; shared by the offscreen
// (OSMesa) and window (GLFW) renderers so both show exactly the same picture.

#include <array>
#include <atomic>
#include <cstdint>

#include "caption_text.hpp"
#include "gl_api.hpp"
#include "page_texture.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::render::detail {

/// Throws std::invalid_argument if the camera or any mesh of `scene` is malformed.
void ValidateScene(const SceneView& scene, const Camera& camera);

/// The pages' textures as GL texture objects of the renderer's context, each uploaded once:
/// the start menu's two pages uploaded every frame were most of its p99. One object per
/// PageCache slot, filled again when the cache keeps another page there; they go with the
/// context.
struct PageTextureObjects {
  struct Slot {
    std::uint64_t serial = 0;  ///< PageTexture::serial it holds (0: none yet)
    GLuint name = 0;
  };
  std::array<Slot, PageCache::kEntries> slots{};
  std::uint64_t uploads = 0;  ///< textures uploaded so far
};

/// What a renderer keeps between frames: the caption's and the labels' layouts, the pages'
/// textures (composed, and as texture objects of its context).
struct TextCaches {
  CaptionCache captions;
  PageCache pages;
  LabelCache labels;
  LabelCache overlay{DefaultCaptionFont(), 50, 30};  // SceneView::overlay: smaller, many lines
  PageTextureObjects page_objects;
};

/// Clears and draws the whole framebuffer (fb_width_px x fb_height_px, GL origin bottom-left)
/// in `mode`; side by side splits it into two halves. The caption goes into every eye view.
/// Expects the context of `gl` to be current. Throws on GL errors.
void DrawFrame(const GlApi& gl, const SceneView& scene, const Camera& camera, StereoMode mode,
               int fb_width_px, int fb_height_px, TextCaches& text);

/// Bumped each time an OSMesa context is made current in this process. OSMesa and Mesa's GLX
/// driver share libglapi's per-thread current dispatch, so a window context must really be
/// re-bound (not just "made current again", which GLVND skips) after an offscreen render;
/// without that the next window draw crashes in Mesa (seen with llvmpipe under Xvfb).
inline std::atomic<std::uint64_t> g_offscreen_binds{0};

}  // namespace handshare::render::detail
