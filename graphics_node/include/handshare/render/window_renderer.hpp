#pragma once
/// @file
/// On-screen rendering of a SceneView in a GLFW window (needs a display; X11 on Debian).

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "handshare/render/image.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::render {

/// What the person at a window did since the last WindowRenderer::TakeInput(): plain data, no
/// GLFW types. Keys are named by the character on them (letters upper case, digits, space),
/// as GLFW names its printable keys.
struct WindowInput {
  struct KeyPress {
    char key = 0;        ///< 'A'..'Z', '0'..'9', ' '
    bool shift = false;  ///< a Shift key was down
    bool repeat = false; ///< the key is held and the system repeats it
  };
  bool focused = false;             ///< the window has the keyboard focus
  bool cursor_inside = false;       ///< the mouse pointer is over the window
  double cursor_x = 0.5;            ///< pointer in the window: 0 left .. 1 right (last known)
  double cursor_y = 0.5;            ///< 0 top .. 1 bottom (last known)
  double wheel_steps = 0.0;         ///< vertical wheel since the last take, + away from the person (up)
  bool left_button = false;         ///< held now
  bool right_button = false;        ///< held now
  std::vector<KeyPress> presses;    ///< printable keys pressed (and repeated) since the last take, in order
};

/// A window that shows one SceneView per Render() call. GLFW requires that every call, including
/// construction and destruction, happens on the process's main thread. Several windows may exist;
/// GLFW is initialized with the first and terminated with the last.
class WindowRenderer {
 public:
  struct Options {
    std::string title = "handshare";
    int width_px = 1280;                     ///< initial window size [screen coordinates].
    int height_px = 720;
    StereoMode stereo = StereoMode::kMono;   ///< side by side splits the window in two halves.
    bool fullscreen = false;                 ///< on the primary monitor, at its current mode.
    bool vsync = true;                       ///< swap interval 1 (otherwise 0).
    bool visible = true;                     ///< false: hidden window (tests, screenshots).
  };

  /// Opens the window. Throws std::runtime_error with GLFW's reason if there is no display or no
  /// OpenGL context can be created.
  explicit WindowRenderer(const Options& options);
  ~WindowRenderer();
  WindowRenderer(const WindowRenderer&) = delete;
  WindowRenderer& operator=(const WindowRenderer&) = delete;

  /// Draws `scene` into the whole framebuffer (its current size sets the aspect ratio; the
  /// camera's width_px / height_px are ignored), swaps buffers and polls window events.
  /// Throws std::invalid_argument for an invalid camera or mesh.
  ///
  /// while_drawing (optional): called again and again, with a time it may wait [s] (1 ms),
  /// between issuing the frame's commands and the swap, while the driver draws them (Mesa's
  /// software rasterizer does so on threads of its own: at 1280 x 720 most of a frame). The
  /// main thread is free meanwhile, so a person's input need not wait for the frame to be
  /// drawn (docs/devices.md, "Motion to photon"): the caller waits for input there
  /// (WaitForInput) and sends it. It must not draw or call Render. Not called where the context
  /// has no fences (OpenGL 3.2 / ARB_sync) or the frame was drawn before the first check.
  void Render(const SceneView& scene, const Camera& camera,
              const std::function<void(double wait_s)>& while_drawing = nullptr);

  /// True once the user asked to close the window (close button, or Escape).
  [[nodiscard]] bool ShouldClose() const;

  /// Current framebuffer size [pixels] (may differ from the window size on HiDPI screens).
  [[nodiscard]] int framebuffer_width_px() const;
  [[nodiscard]] int framebuffer_height_px() const;

  /// Like Render(), and also returns the drawn frame (row 0 at the top), read back before the
  /// swap: screenshots and tests. (Reading the front buffer after the swap is unreliable: its
  /// pixels belong to the window system.)
  [[nodiscard]] ImageRgb8 RenderAndCapture(const SceneView& scene, const Camera& camera);

  /// What the person did at the window since the last call (events arrive while Render polls
  /// them). Main thread only.
  [[nodiscard]] WindowInput TakeInput();

  /// Waits up to timeout_s for the person's input (pointer motion, a button, a key, the wheel,
  /// focus) and handles the window's events meanwhile; true if input arrived since the last
  /// call (take it with TakeInput). The time between two frames, spent awake for input: a
  /// move reaches the hand at once, not when the next frame is due. Main thread only.
  [[nodiscard]] bool WaitForInput(double timeout_s);

  /// Ends a WaitForInput early, from any thread (it then returns false unless input came too).
  static void Wake();

  /// True if GLFW can be initialized here (a display is reachable); never throws.
  [[nodiscard]] static bool DisplayAvailable() noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handshare::render
