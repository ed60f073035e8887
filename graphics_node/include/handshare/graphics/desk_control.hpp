#pragma once
/// The desk: how a person's mouse and keyboard at their own view (graphics_node --view user:U
/// --input desk) become a hand target (hand base pose and each finger's closure), which the
/// view sends to that user's haptic node (haptic_node --device desk) as a DeskInput. The
/// mapping (docs/devices.md, "The desk: mouse and keyboard"):
///
///   mouse pointer        hand base left/right (x) and down/up (z), absolutely: the window's
///                        centre is the home position, its edges half_width_m / half_height_m away
///   wheel, W / S         away from you / towards you (y), depth_step_m a notch or a press
///   A / D, R / F         turn the hand left / right (about z), tilt it down / up (about x),
///                        turn_step_rad a press
///   left / right button  close / open the whole hand, held: closure_rate_per_s
///   C / V                close / open the whole hand by closure_step a press
///   1 .. 5               close the thumb .. little finger by closure_step a press;
///                        with Shift: open it
///   O                    open every finger
///   0                    back home: depth, turn and tilt to zero
///   H                    show or hide the help; Esc closes the window
/// Keys repeat while held (the system's key repeat), so a held key moves on.
///
/// No DDS and no GLFW here: WindowInput in, plain numbers out, unit-tested.
#include <array>
#include <string>

#include <Eigen/Geometry>

#include "handshare/common/hand.hpp"
#include "handshare/render/window_renderer.hpp"

namespace handshare::graphics {

/// What a person's input asks of their hand: sent as a DeskInput to their haptic node, from the
/// desk (DeskControl) or a gamepad (GamepadControl, gamepad_control.hpp).
struct HandTarget {
  Eigen::Vector3d p_WH = Eigen::Vector3d::Zero();          ///< hand base in W [m]
  Eigen::Quaterniond q_WH = Eigen::Quaterniond::Identity();
  std::array<double, common::kFingers> closure{};          ///< per finger, thumb first: 0 open .. 1 closed
  bool focused = false;                                    ///< false: the hand is released
};

struct DeskControlConfig {
  Eigen::Vector3d home_W{0.0, -0.20, 0.15};  ///< hand base with the pointer at the window's centre [m]
  double half_width_m = 0.30;                 ///< pointer at the left / right edge: x -/+ this [m]
  double half_height_m = 0.15;                ///< pointer at the bottom / top edge: z -/+ this [m]
  double depth_step_m = 0.01;                 ///< a wheel notch or a W / S press [m]
  double min_depth_m = -0.25, max_depth_m = 0.45;  ///< y offset from home, bounds [m]
  double turn_step_rad = 0.0873;              ///< 5 degrees a press
  double max_turn_rad = 1.5708;               ///< +- 90 degrees about z
  double max_tilt_rad = 1.0472;               ///< +- 60 degrees about x
  double closure_step = 0.1;                  ///< a C / V / digit press
  double closure_rate_per_s = 1.0;            ///< a mouse button held
};

class DeskControl {
 public:
  explicit DeskControl(DeskControlConfig config = {});

  /// One frame's input, dt_s after the last (for held buttons; clamped to [0, 0.1] s).
  void Apply(const render::WindowInput& in, double dt_s);

  /// The hand base target in W.
  [[nodiscard]] Eigen::Vector3d p_WH() const;
  [[nodiscard]] Eigen::Quaterniond q_WH() const;
  /// Per finger, thumb first: 0 open .. 1 closed.
  [[nodiscard]] const std::array<double, common::kFingers>& closure() const { return closure_; }
  /// False while the window has no keyboard focus: the haptic node releases the hand.
  [[nodiscard]] bool focused() const { return focused_; }
  /// All of the above, as sent.
  [[nodiscard]] HandTarget target() const { return {p_WH(), q_WH(), closure_, focused_}; }
  [[nodiscard]] bool help_shown() const { return help_; }
  [[nodiscard]] const DeskControlConfig& config() const { return config_; }

  /// The key mapping as the view shows it (the help overlay).
  [[nodiscard]] static std::string HelpText();

 private:
  DeskControlConfig config_;
  double cursor_x_ = 0.5, cursor_y_ = 0.5;
  double depth_m_ = 0.0;
  double turn_rad_ = 0.0, tilt_rad_ = 0.0;
  std::array<double, common::kFingers> closure_{};
  bool focused_ = false;
  bool help_ = true;
};

}  // namespace handshare::graphics
