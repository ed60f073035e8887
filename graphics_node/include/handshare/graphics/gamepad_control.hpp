#pragma once
/// The gamepad: how a person's game controller at their own view (graphics_node --view user:U
/// --input gamepad) becomes a hand target, sent to their haptic node (haptic_node --device desk)
/// exactly as the desk's mouse and keyboard are (DeskInput). The mapping (docs/devices.md, "The
/// gamepad"):
///
///   left stick          hand base left/right (x) and away/towards you (y), speed_m_per_s at full tilt
///   right stick         up/down (z) and turn the hand (about z)
///   right trigger       close the whole hand, by how far it is pulled (released: open)
///   left trigger        pinch: close thumb and index only, by how far it is pulled
///   Back                home: the hand back to where it started, level
///   rumble              low motor: the weight the hand holds (full at rumble_full_weight_N);
///                       high motor: the largest fingertip force (full at the device limit)
/// A controller unplugged releases the hand (the target's focused is false), as a window
/// without focus does.
///
/// No DDS and no SDL here: a render::GamepadState in, plain numbers out, unit-tested.
#include <array>
#include <string>

#include <Eigen/Geometry>

#include "handshare/common/hand.hpp"
#include "handshare/graphics/desk_control.hpp"
#include "handshare/render/gamepad.hpp"

namespace handshare::graphics {

struct GamepadControlConfig {
  Eigen::Vector3d home_W{0.0, -0.20, 0.15};          ///< where the hand base starts [m]
  Eigen::Vector3d half_extent_m{0.30, 0.35, 0.15};   ///< the hand stays within home -+ this [m]
  double speed_m_per_s = 0.25;                       ///< a stick at full tilt
  double turn_rate_rad_per_s = 1.5;
  double max_turn_rad = 1.5708;
  double deadzone = 0.15;                            ///< stick tilts below this do nothing
  double rumble_full_weight_N = 2.0;                 ///< held weight at which the low motor is full
  double max_force_N = 3.5;                          ///< fingertip force at which the high motor is full
};

/// Motor levels in [0, 1].
struct GamepadRumble {
  double low = 0.0;
  double high = 0.0;
};

class GamepadControl {
 public:
  explicit GamepadControl(GamepadControlConfig config = {});

  /// One frame's reading, dt_s after the last (clamped to [0, 0.1] s: a stalled frame does not
  /// throw the hand across the table).
  void Apply(const render::GamepadState& in, double dt_s);
  [[nodiscard]] HandTarget target() const;

  /// What the motors say for the weight the hand holds and the largest fingertip force [N].
  [[nodiscard]] GamepadRumble RumbleFor(double held_weight_N, double max_fingertip_force_N) const;
  /// The mapping as the view shows it (the help overlay).
  [[nodiscard]] static std::string HelpText();

 private:
  double Stick(double v) const;

  GamepadControlConfig config_;
  Eigen::Vector3d offset_m_ = Eigen::Vector3d::Zero();
  double turn_rad_ = 0.0;
  std::array<double, common::kFingers> closure_{};
  bool connected_ = false;
};

}  // namespace handshare::graphics
