#include "handshare/graphics/desk_control.hpp"

#include <algorithm>

namespace handshare::graphics {

DeskControl::DeskControl(DeskControlConfig config) : config_(std::move(config)) {}

void DeskControl::Apply(const render::WindowInput& in, double dt_s) {
  const DeskControlConfig& c = config_;
  focused_ = in.focused;
  cursor_x_ = std::clamp(in.cursor_x, 0.0, 1.0);
  cursor_y_ = std::clamp(in.cursor_y, 0.0, 1.0);
  const auto close_all = [&](double by) {
    for (double& f : closure_) f = std::clamp(f + by, 0.0, 1.0);
  };
  // Input from a window without focus is not the person's: keys and wheel go elsewhere.
  if (!focused_) return;
  depth_m_ = std::clamp(depth_m_ + c.depth_step_m * in.wheel_steps, c.min_depth_m, c.max_depth_m);
  const double held_s = std::clamp(dt_s, 0.0, 0.1);
  if (in.left_button != in.right_button) close_all((in.left_button ? 1.0 : -1.0) * c.closure_rate_per_s * held_s);
  for (const render::WindowInput::KeyPress& press : in.presses) {
    switch (press.key) {
      case 'W': depth_m_ = std::min(depth_m_ + c.depth_step_m, c.max_depth_m); break;
      case 'S': depth_m_ = std::max(depth_m_ - c.depth_step_m, c.min_depth_m); break;
      case 'A': turn_rad_ = std::min(turn_rad_ + c.turn_step_rad, c.max_turn_rad); break;
      case 'D': turn_rad_ = std::max(turn_rad_ - c.turn_step_rad, -c.max_turn_rad); break;
      case 'R': tilt_rad_ = std::max(tilt_rad_ - c.turn_step_rad, -c.max_tilt_rad); break;
      case 'F': tilt_rad_ = std::min(tilt_rad_ + c.turn_step_rad, c.max_tilt_rad); break;
      case 'C': close_all(c.closure_step); break;
      case 'V': close_all(-c.closure_step); break;
      case 'O': closure_.fill(0.0); break;
      case '0': depth_m_ = turn_rad_ = tilt_rad_ = 0.0; break;
      case 'H':
        if (!press.repeat) help_ = !help_;
        break;
      default:
        if (press.key >= '1' && press.key <= '5') {
          double& f = closure_[static_cast<std::size_t>(press.key - '1')];
          f = std::clamp(f + (press.shift ? -c.closure_step : c.closure_step), 0.0, 1.0);
        }
        break;
    }
  }
}

Eigen::Vector3d DeskControl::p_WH() const {
  const DeskControlConfig& c = config_;
  return c.home_W + Eigen::Vector3d((2.0 * cursor_x_ - 1.0) * c.half_width_m, depth_m_,
                                    (1.0 - 2.0 * cursor_y_) * c.half_height_m);
}

Eigen::Quaterniond DeskControl::q_WH() const {
  // Turn about the world's vertical, then tilt about the hand's own x (fingers down for R).
  return Eigen::Quaterniond(Eigen::AngleAxisd(turn_rad_, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(tilt_rad_, Eigen::Vector3d::UnitX()));
}

std::string DeskControl::HelpText() {
  return "Your hand at the desk (H hides this)\n"
         "mouse: hand left/right, up/down\n"
         "wheel or W/S: away / towards you\n"
         "A/D: turn left/right   R/F: tilt down/up\n"
         "left/right button held: close/open hand\n"
         "C/V: close/open a step   O: open all\n"
         "1-5: close thumb..little, Shift+1-5: open\n"
         "0: home   Esc: quit\n"
         "fingertips: colour and arrow = force (arrow 1 cm per N)";
}

}  // namespace handshare::graphics
