#include "handshare/render/gamepad.hpp"

#include <SDL2/SDL.h>

#include <algorithm>
#include <stdexcept>

namespace handshare::render {

namespace {
SDL_GameController* Pad(void* p) { return static_cast<SDL_GameController*>(p); }

double Axis(SDL_GameController* pad, SDL_GameControllerAxis axis) {
  return std::clamp(static_cast<double>(SDL_GameControllerGetAxis(pad, axis)) / 32767.0, -1.0, 1.0);
}

std::uint16_t Motor(double level) { return static_cast<std::uint16_t>(std::clamp(level, 0.0, 1.0) * 65535.0 + 0.5); }
}  // namespace

Gamepad::Gamepad() {
  // Controllers without a window: no video subsystem, and no signal handlers of SDL's own.
  SDL_SetHint(SDL_HINT_NO_SIGNAL_HANDLERS, "1");
  SDL_SetHint(SDL_HINT_JOYSTICK_ALLOW_BACKGROUND_EVENTS, "1");
  if (SDL_InitSubSystem(SDL_INIT_GAMECONTROLLER) != 0) {
    throw std::runtime_error(std::string("gamepad: SDL cannot start its game-controller subsystem: ") + SDL_GetError());
  }
}

Gamepad::~Gamepad() {
  if (controller_ != nullptr) SDL_GameControllerClose(Pad(controller_));
  SDL_QuitSubSystem(SDL_INIT_GAMECONTROLLER);
}

GamepadState Gamepad::Poll() {
  SDL_GameControllerUpdate();
  if (controller_ != nullptr && !SDL_GameControllerGetAttached(Pad(controller_))) {
    SDL_GameControllerClose(Pad(controller_));  // unplugged
    controller_ = nullptr;
  }
  if (controller_ == nullptr) {
    for (int i = 0; i < SDL_NumJoysticks(); ++i) {
      if (!SDL_IsGameController(i)) continue;
      controller_ = SDL_GameControllerOpen(i);
      if (controller_ != nullptr) break;
    }
    if (controller_ == nullptr) return {};
    SDL_GameControllerUpdate();
  }
  SDL_GameController* pad = Pad(controller_);
  GamepadState s;
  s.connected = true;
  const char* name = SDL_GameControllerName(pad);
  s.name = name != nullptr ? name : "";
  s.left_x = Axis(pad, SDL_CONTROLLER_AXIS_LEFTX);
  s.left_y = -Axis(pad, SDL_CONTROLLER_AXIS_LEFTY);  // SDL: down is positive
  s.right_x = Axis(pad, SDL_CONTROLLER_AXIS_RIGHTX);
  s.right_y = -Axis(pad, SDL_CONTROLLER_AXIS_RIGHTY);
  s.left_trigger = std::max(0.0, Axis(pad, SDL_CONTROLLER_AXIS_TRIGGERLEFT));
  s.right_trigger = std::max(0.0, Axis(pad, SDL_CONTROLLER_AXIS_TRIGGERRIGHT));
  s.south = SDL_GameControllerGetButton(pad, SDL_CONTROLLER_BUTTON_A) != 0;
  s.back = SDL_GameControllerGetButton(pad, SDL_CONTROLLER_BUTTON_BACK) != 0;
  return s;
}

bool Gamepad::Rumble(double low, double high, std::uint32_t duration_ms) {
  if (controller_ == nullptr) return false;
  return SDL_GameControllerRumble(Pad(controller_), Motor(low), Motor(high), duration_ms) == 0;
}

}  // namespace handshare::render
