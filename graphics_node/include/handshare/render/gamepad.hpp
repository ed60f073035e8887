#pragma once
/// A gamepad through SDL2's game-controller API (a Debian package, libsdl2): the first controller
/// SDL finds (an Xbox or PlayStation pad, or any it has a mapping for), its sticks, triggers and
/// buttons, and its rumble. No middleware; used by a user's own view (graphics_node --input
/// gamepad). Call it from one thread. Tests drive it with SDL's virtual joysticks
/// (SDL_JoystickAttachVirtualEx), since test machines have no input devices.
#include <cstdint>
#include <string>

namespace handshare::render {

/// One reading. Sticks in [-1, 1] (x to the right, y up: pushed away from the person), triggers
/// in [0, 1]; connected false when no controller is plugged in (every other field zero).
struct GamepadState {
  bool connected = false;
  std::string name;  ///< the controller's name, as SDL knows it
  double left_x = 0.0, left_y = 0.0, right_x = 0.0, right_y = 0.0;
  double left_trigger = 0.0, right_trigger = 0.0;
  bool south = false;  ///< A on an Xbox pad, cross on a PlayStation's
  bool back = false;   ///< Back / Select / Share
};

class Gamepad {
 public:
  /// Starts SDL's game-controller subsystem; throws std::runtime_error with SDL's reason.
  Gamepad();
  ~Gamepad();
  Gamepad(const Gamepad&) = delete;
  Gamepad& operator=(const Gamepad&) = delete;

  /// Reads the controller now: opens the first one when none is open, lets go of one that was
  /// unplugged (connected false until another is plugged in).
  [[nodiscard]] GamepadState Poll();
  /// Rumbles the open controller: low- and high-frequency motors in [0, 1], for duration_ms.
  /// False when no controller is open or it cannot rumble.
  bool Rumble(double low, double high, std::uint32_t duration_ms);

 private:
  void* controller_ = nullptr;  // SDL_GameController*
};

}  // namespace handshare::render
