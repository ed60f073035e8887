// render::Gamepad against SDL's virtual joystick (the test machines have no input devices): a
// game controller plugged in by the test, its sticks and triggers read as the person pushed
// them, its rumble reaching the controller, and its unplugging seen.
#include "handshare/render/gamepad.hpp"

#include <gtest/gtest.h>

#include <SDL2/SDL.h>

namespace handshare::render {
namespace {

struct Motors {
  int calls = 0;
  Uint16 low = 0, high = 0;
};

int RecordRumble(void* userdata, Uint16 low, Uint16 high) {
  auto* m = static_cast<Motors*>(userdata);
  ++m->calls;
  m->low = low;
  m->high = high;
  return 0;
}

/// A virtual game controller: SDL maps its axes and buttons in SDL's own order.
class VirtualPad {
 public:
  explicit VirtualPad(Motors* motors) {
    SDL_VirtualJoystickDesc desc;
    SDL_zero(desc);
    desc.version = SDL_VIRTUAL_JOYSTICK_DESC_VERSION;
    desc.type = SDL_JOYSTICK_TYPE_GAMECONTROLLER;
    desc.naxes = SDL_CONTROLLER_AXIS_MAX;
    desc.nbuttons = SDL_CONTROLLER_BUTTON_MAX;
    desc.name = "handshare test pad";
    desc.userdata = motors;
    desc.Rumble = RecordRumble;
    index_ = SDL_JoystickAttachVirtualEx(&desc);
    EXPECT_GE(index_, 0) << SDL_GetError();
    joystick_ = SDL_JoystickOpen(index_);
    EXPECT_NE(joystick_, nullptr) << SDL_GetError();
  }
  ~VirtualPad() { Unplug(); }
  void Axis(SDL_GameControllerAxis axis, Sint16 value) { SDL_JoystickSetVirtualAxis(joystick_, axis, value); }
  void Button(SDL_GameControllerButton button, bool down) { SDL_JoystickSetVirtualButton(joystick_, button, down ? 1 : 0); }
  void Unplug() {
    if (joystick_ == nullptr) return;
    SDL_JoystickClose(joystick_);
    joystick_ = nullptr;
    SDL_JoystickDetachVirtual(index_);
  }

 private:
  int index_ = -1;
  SDL_Joystick* joystick_ = nullptr;
};

TEST(Gamepad, ReadsSticksTriggersAndButtonsRumblesAndSeesItUnplugged) {
  Gamepad gamepad;  // starts SDL's game-controller subsystem
  EXPECT_FALSE(gamepad.Poll().connected);  // nothing plugged in
  EXPECT_FALSE(gamepad.Rumble(1.0, 1.0, 100));
  Motors motors;
  VirtualPad pad(&motors);
  pad.Axis(SDL_CONTROLLER_AXIS_LEFTX, 32767);
  pad.Axis(SDL_CONTROLLER_AXIS_LEFTY, -32768);   // pushed away from the person: SDL's "up"
  pad.Axis(SDL_CONTROLLER_AXIS_RIGHTY, 16384);   // pulled half towards the person
  pad.Axis(SDL_CONTROLLER_AXIS_TRIGGERRIGHT, 32767);
  pad.Button(SDL_CONTROLLER_BUTTON_BACK, true);
  GamepadState s = gamepad.Poll();
  ASSERT_TRUE(s.connected);
  EXPECT_EQ(s.name, "handshare test pad");
  EXPECT_NEAR(s.left_x, 1.0, 1e-4);
  EXPECT_NEAR(s.left_y, 1.0, 1e-4);
  EXPECT_NEAR(s.right_y, -0.5, 1e-3);
  EXPECT_NEAR(s.right_x, 0.0, 1e-4);
  EXPECT_NEAR(s.right_trigger, 1.0, 1e-4);
  EXPECT_NEAR(s.left_trigger, 0.0, 1e-4);
  EXPECT_TRUE(s.back);
  EXPECT_FALSE(s.south);
  // Rumble reaches the controller's motors.
  EXPECT_TRUE(gamepad.Rumble(0.5, 0.25, 100));
  EXPECT_GE(motors.calls, 1);
  EXPECT_NEAR(motors.low, 32768, 2);
  EXPECT_NEAR(motors.high, 16384, 2);
  // Unplugged: no controller, and no rumble.
  pad.Unplug();
  s = gamepad.Poll();
  EXPECT_FALSE(s.connected);
  EXPECT_EQ(s.left_x, 0.0);
  EXPECT_FALSE(gamepad.Rumble(1.0, 1.0, 100));
}

}  // namespace
}  // namespace handshare::render
