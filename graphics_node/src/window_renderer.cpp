#include "handshare/render/window_renderer.hpp"

#include <GLFW/glfw3.h>

#include <algorithm>
#include <mutex>
#include <stdexcept>
#include <string>

#include "gl_api.hpp"
#include "scene_drawer.hpp"

namespace handshare::render {

namespace {

// GLFW is process-global: initialize with the first window, terminate with the last.
std::mutex g_glfw_mutex;
int g_glfw_users = 0;
std::string g_glfw_last_error;  // guarded by g_glfw_mutex while a constructor runs

void RecordGlfwError(int code, const char* description) {
  g_glfw_last_error = "GLFW error " + std::to_string(code) + ": " + (description ? description : "");
}

// Call with g_glfw_mutex held. Returns false (and leaves the reason in g_glfw_last_error).
bool AcquireGlfw() {
  if (g_glfw_users == 0) {
    glfwSetErrorCallback(RecordGlfwError);
    g_glfw_last_error.clear();
    if (glfwInit() == GLFW_FALSE) return false;
  }
  ++g_glfw_users;
  return true;
}

void ReleaseGlfw() {
  if (--g_glfw_users == 0) glfwTerminate();
}

}  // namespace

struct WindowRenderer::Impl {
  GLFWwindow* window = nullptr;
  StereoMode stereo = StereoMode::kMono;
  detail::GlApi gl;
  detail::TextCaches text;  // the caption's layout, the pages' textures
  std::uint64_t offscreen_binds_seen = 0;
  // Input events since the last TakeInput (GLFW's callbacks, on the main thread in PollEvents).
  double wheel_steps = 0.0;
  std::vector<WindowInput::KeyPress> presses;
  double cursor_x = 0.5, cursor_y = 0.5;
  bool input_arrived = false;  // any input event since the last WaitForInput

  // Makes the window's context current; forces a real re-bind if an OSMesa context was bound
  // since (see detail::g_offscreen_binds).
  void MakeCurrent() {
    const std::uint64_t binds = detail::g_offscreen_binds.load();
    if (binds != offscreen_binds_seen) {
      glfwMakeContextCurrent(nullptr);
      offscreen_binds_seen = binds;
    }
    glfwMakeContextCurrent(window);
  }
};

WindowRenderer::WindowRenderer(const Options& options) : impl_(std::make_unique<Impl>()) {
  std::lock_guard lock(g_glfw_mutex);
  if (!AcquireGlfw()) {
    throw std::runtime_error("WindowRenderer: cannot initialize GLFW (no display?): " +
                             g_glfw_last_error);
  }
  glfwDefaultWindowHints();
  // A compatibility context: the scene drawer uses fixed-function OpenGL.
  glfwWindowHint(GLFW_CLIENT_API, GLFW_OPENGL_API);
  glfwWindowHint(GLFW_DEPTH_BITS, 24);
  glfwWindowHint(GLFW_VISIBLE, options.visible ? GLFW_TRUE : GLFW_FALSE);
  GLFWmonitor* monitor = options.fullscreen ? glfwGetPrimaryMonitor() : nullptr;
  int width = options.width_px;
  int height = options.height_px;
  if (monitor != nullptr) {
    const GLFWvidmode* mode = glfwGetVideoMode(monitor);
    width = mode->width;
    height = mode->height;
  }
  impl_->window = glfwCreateWindow(width, height, options.title.c_str(), monitor, nullptr);
  if (impl_->window == nullptr) {
    const std::string reason = g_glfw_last_error;
    ReleaseGlfw();
    throw std::runtime_error("WindowRenderer: cannot create a " + std::to_string(width) + " x " +
                             std::to_string(height) + " OpenGL window: " + reason);
  }
  impl_->stereo = options.stereo;
  glfwSetWindowUserPointer(impl_->window, impl_.get());
  glfwSetKeyCallback(impl_->window, [](GLFWwindow* window, int key, int, int action, int mods) {
    if (key == GLFW_KEY_ESCAPE && action == GLFW_PRESS) glfwSetWindowShouldClose(window, GLFW_TRUE);
    // Printable keys GLFW names by their character: space, digits, letters (upper case).
    const bool printable = key == GLFW_KEY_SPACE || (key >= GLFW_KEY_0 && key <= GLFW_KEY_9) ||
                           (key >= GLFW_KEY_A && key <= GLFW_KEY_Z);
    if (!printable || action == GLFW_RELEASE) return;
    auto* impl = static_cast<Impl*>(glfwGetWindowUserPointer(window));
    impl->input_arrived = true;
    if (impl->presses.size() < 256) {  // a stuck repeat between two takes cannot grow it without end
      impl->presses.push_back({static_cast<char>(key), (mods & GLFW_MOD_SHIFT) != 0, action == GLFW_REPEAT});
    }
  });
  glfwSetScrollCallback(impl_->window, [](GLFWwindow* window, double, double dy) {
    auto* impl = static_cast<Impl*>(glfwGetWindowUserPointer(window));
    impl->wheel_steps += dy;
    impl->input_arrived = true;
  });
  // Pointer motion, buttons and focus are read when taken (TakeInput); these only say that
  // something arrived, so that WaitForInput wakes for it.
  glfwSetCursorPosCallback(impl_->window, [](GLFWwindow* window, double, double) {
    static_cast<Impl*>(glfwGetWindowUserPointer(window))->input_arrived = true;
  });
  glfwSetMouseButtonCallback(impl_->window, [](GLFWwindow* window, int, int, int) {
    static_cast<Impl*>(glfwGetWindowUserPointer(window))->input_arrived = true;
  });
  glfwSetWindowFocusCallback(impl_->window, [](GLFWwindow* window, int) {
    static_cast<Impl*>(glfwGetWindowUserPointer(window))->input_arrived = true;
  });
  impl_->offscreen_binds_seen = detail::g_offscreen_binds.load();
  glfwMakeContextCurrent(impl_->window);
  glfwSwapInterval(options.vsync ? 1 : 0);
  try {
    impl_->gl.Load([](const char* name) -> detail::GlApi::Proc { return glfwGetProcAddress(name); });
  } catch (...) {
    glfwDestroyWindow(impl_->window);
    ReleaseGlfw();
    throw;
  }
}

WindowRenderer::~WindowRenderer() {
  std::lock_guard lock(g_glfw_mutex);
  glfwDestroyWindow(impl_->window);
  ReleaseGlfw();
}

void WindowRenderer::Render(const SceneView& scene, const Camera& camera,
                            const std::function<void(double wait_s)>& while_drawing) {
  impl_->MakeCurrent();
  int width_px = 0;
  int height_px = 0;
  glfwGetFramebufferSize(impl_->window, &width_px, &height_px);
  detail::DrawFrame(impl_->gl, scene, camera, impl_->stereo, width_px, height_px, impl_->text);
  const detail::GlApi& gl = impl_->gl;
  if (while_drawing && gl.FenceSync != nullptr) {
    // The frame's commands end with a fence and go to the driver; until it has drawn them, the
    // caller's turn (at most kMaxOverlap_s, so that a driver that never signals cannot stall the
    // window: the swap then waits as it always did).
    constexpr double kPoll_s = 1e-3;
    constexpr double kMaxOverlap_s = 0.25;
    GLsync fence = gl.FenceSync(GL_SYNC_GPU_COMMANDS_COMPLETE, 0);
    gl.Flush();
    const double until_s = glfwGetTime() + kMaxOverlap_s;
    while (fence != nullptr && gl.ClientWaitSync(fence, 0, 0) == GL_TIMEOUT_EXPIRED && glfwGetTime() < until_s) {
      while_drawing(kPoll_s);
    }
    if (fence != nullptr) gl.DeleteSync(fence);
  }
  glfwSwapBuffers(impl_->window);
  glfwPollEvents();
}

ImageRgb8 WindowRenderer::RenderAndCapture(const SceneView& scene, const Camera& camera) {
  impl_->MakeCurrent();
  int width_px = 0;
  int height_px = 0;
  glfwGetFramebufferSize(impl_->window, &width_px, &height_px);
  detail::DrawFrame(impl_->gl, scene, camera, impl_->stereo, width_px, height_px, impl_->text);
  ImageRgb8 image(width_px, height_px);
  if (width_px > 0 && height_px > 0) {
    ImageRgb8 bottom_up(width_px, height_px);
    impl_->gl.ReadBuffer(GL_BACK);
    impl_->gl.PixelStorei(GL_PACK_ALIGNMENT, 1);
    impl_->gl.ReadPixels(0, 0, width_px, height_px, GL_RGB, GL_UNSIGNED_BYTE, bottom_up.rgb.data());
    impl_->gl.CheckError("reading the back buffer");
    // OpenGL rows start at the bottom; images start at the top.
    const std::size_t row_bytes = 3 * static_cast<std::size_t>(width_px);
    for (int row = 0; row < height_px; ++row) {
      const std::uint8_t* src = bottom_up.At(0, height_px - 1 - row);
      std::copy(src, src + row_bytes, image.At(0, row));
    }
  }
  glfwSwapBuffers(impl_->window);
  glfwPollEvents();
  return image;
}

WindowInput WindowRenderer::TakeInput() {
  WindowInput in;
  in.focused = glfwGetWindowAttrib(impl_->window, GLFW_FOCUSED) != 0;
  in.cursor_inside = glfwGetWindowAttrib(impl_->window, GLFW_HOVERED) != 0;
  int width = 0;
  int height = 0;
  glfwGetWindowSize(impl_->window, &width, &height);
  if (in.cursor_inside && width > 0 && height > 0) {
    double x = 0.0;
    double y = 0.0;
    glfwGetCursorPos(impl_->window, &x, &y);
    impl_->cursor_x = std::clamp(x / width, 0.0, 1.0);
    impl_->cursor_y = std::clamp(y / height, 0.0, 1.0);
  }
  in.cursor_x = impl_->cursor_x;
  in.cursor_y = impl_->cursor_y;
  in.left_button = glfwGetMouseButton(impl_->window, GLFW_MOUSE_BUTTON_LEFT) == GLFW_PRESS;
  in.right_button = glfwGetMouseButton(impl_->window, GLFW_MOUSE_BUTTON_RIGHT) == GLFW_PRESS;
  in.wheel_steps = impl_->wheel_steps;
  impl_->wheel_steps = 0.0;
  in.presses.swap(impl_->presses);
  return in;
}

bool WindowRenderer::WaitForInput(double timeout_s) {
  if (!impl_->input_arrived && timeout_s > 0.0) glfwWaitEventsTimeout(timeout_s);
  if (!impl_->input_arrived) glfwPollEvents();  // woken for another window or an empty event
  const bool arrived = impl_->input_arrived;
  impl_->input_arrived = false;
  return arrived;
}

void WindowRenderer::Wake() { glfwPostEmptyEvent(); }

bool WindowRenderer::ShouldClose() const { return glfwWindowShouldClose(impl_->window) != 0; }

int WindowRenderer::framebuffer_width_px() const {
  int width_px = 0;
  glfwGetFramebufferSize(impl_->window, &width_px, nullptr);
  return width_px;
}

int WindowRenderer::framebuffer_height_px() const {
  int height_px = 0;
  glfwGetFramebufferSize(impl_->window, nullptr, &height_px);
  return height_px;
}

bool WindowRenderer::DisplayAvailable() noexcept {
  std::lock_guard lock(g_glfw_mutex);
  if (!AcquireGlfw()) return false;
  ReleaseGlfw();
  return true;
}

}  // namespace handshare::render
