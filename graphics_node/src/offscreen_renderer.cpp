#include "handshare/render/offscreen_renderer.hpp"

#include <GL/osmesa.h>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "gl_api.hpp"
#include "scene_drawer.hpp"

namespace handshare::render {

struct OffscreenRenderer::Impl {
  OSMesaContext context = nullptr;
  detail::GlApi gl;
  detail::TextCaches text;  // the caption's layout, the pages' textures
  std::vector<std::uint8_t> rgba;  // OSMesa colour buffer, bottom row first.

  Impl() {
    // RGBA, 24-bit depth, no stencil or accumulation buffer, no sharing.
    context = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
    if (context == nullptr) {
      throw std::runtime_error("OffscreenRenderer: OSMesaCreateContextExt failed (Mesa OSMesa)");
    }
    gl.Load([](const char* name) -> detail::GlApi::Proc { return OSMesaGetProcAddress(name); });
  }
  ~Impl() {
    if (context != nullptr) OSMesaDestroyContext(context);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;
};

OffscreenRenderer::OffscreenRenderer() : impl_(std::make_unique<Impl>()) {}
OffscreenRenderer::~OffscreenRenderer() = default;
OffscreenRenderer::OffscreenRenderer(OffscreenRenderer&&) noexcept = default;
OffscreenRenderer& OffscreenRenderer::operator=(OffscreenRenderer&&) noexcept = default;

ImageRgb8 OffscreenRenderer::Render(const SceneView& scene, const Camera& camera, StereoMode mode) {
  detail::ValidateScene(scene, camera);
  const int width_px = mode == StereoMode::kSideBySide ? 2 * camera.width_px : camera.width_px;
  const int height_px = camera.height_px;
  impl_->rgba.resize(4 * static_cast<std::size_t>(width_px) * static_cast<std::size_t>(height_px));
  ++detail::g_offscreen_binds;
  if (OSMesaMakeCurrent(impl_->context, impl_->rgba.data(), GL_UNSIGNED_BYTE, width_px,
                        height_px) == GL_FALSE) {
    throw std::runtime_error("OffscreenRenderer: OSMesaMakeCurrent failed for " +
                             std::to_string(width_px) + " x " + std::to_string(height_px) + " px");
  }
  detail::DrawFrame(impl_->gl, scene, camera, mode, width_px, height_px, impl_->text);
  impl_->gl.Finish();

  // OSMesa's buffer starts at the bottom row; images start at the top.
  ImageRgb8 image(width_px, height_px);
  for (int row = 0; row < height_px; ++row) {
    const std::uint8_t* src =
        impl_->rgba.data() + 4 * static_cast<std::size_t>(height_px - 1 - row) * width_px;
    std::uint8_t* dst = image.At(0, row);
    for (int col = 0; col < width_px; ++col) {
      std::memcpy(dst + 3 * col, src + 4 * col, 3);
    }
  }
  return image;
}

const CaptionStats& OffscreenRenderer::last_caption() const { return impl_->text.captions.stats(); }

std::uint64_t OffscreenRenderer::page_uploads() const { return impl_->text.page_objects.uploads; }

}  // namespace handshare::render
