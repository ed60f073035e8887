#include "handshare/graphics/gamepad_control.hpp"

#include <algorithm>
#include <cmath>

namespace handshare::graphics {

GamepadControl::GamepadControl(GamepadControlConfig config) : config_(std::move(config)) {}

double GamepadControl::Stick(double v) const {
  // Outside the dead zone, rescaled so that the rate starts from zero at its edge.
  const double a = std::abs(v);
  if (!(a > config_.deadzone)) return 0.0;
  return std::copysign(std::min(1.0, (a - config_.deadzone) / (1.0 - config_.deadzone)), v);
}

void GamepadControl::Apply(const render::GamepadState& in, double dt_s) {
  const GamepadControlConfig& c = config_;
  connected_ = in.connected;
  if (!connected_) return;  // unplugged: the target stays, released
  const double dt = std::clamp(dt_s, 0.0, 0.1);
  const double step = c.speed_m_per_s * dt;
  offset_m_ += step * Eigen::Vector3d(Stick(in.left_x), Stick(in.left_y), Stick(in.right_y));
  offset_m_ = offset_m_.cwiseMax(-c.half_extent_m).cwiseMin(c.half_extent_m);
  turn_rad_ = std::clamp(turn_rad_ - c.turn_rate_rad_per_s * dt * Stick(in.right_x), -c.max_turn_rad, c.max_turn_rad);
  if (in.back) {
    offset_m_.setZero();
    turn_rad_ = 0.0;
  }
  const double hand = std::clamp(in.right_trigger, 0.0, 1.0);
  const double pinch = std::max(hand, std::clamp(in.left_trigger, 0.0, 1.0));
  closure_.fill(hand);
  closure_[0] = closure_[1] = pinch;  // thumb and index
}

HandTarget GamepadControl::target() const {
  HandTarget t;
  t.p_WH = config_.home_W + offset_m_;
  t.q_WH = Eigen::Quaterniond(Eigen::AngleAxisd(turn_rad_, Eigen::Vector3d::UnitZ()));
  t.closure = closure_;
  t.focused = connected_;
  return t;
}

GamepadRumble GamepadControl::RumbleFor(double held_weight_N, double max_fingertip_force_N) const {
  GamepadRumble r;
  if (std::isfinite(held_weight_N)) r.low = std::clamp(held_weight_N / config_.rumble_full_weight_N, 0.0, 1.0);
  if (std::isfinite(max_fingertip_force_N)) r.high = std::clamp(max_fingertip_force_N / config_.max_force_N, 0.0, 1.0);
  return r;
}

std::string GamepadControl::HelpText() {
  return "Your hand on the gamepad\n"
         "left stick: left/right, away/towards you    right stick: up/down, turn\n"
         "right trigger: close the hand    left trigger: pinch (thumb and index)\n"
         "Back: home    rumble: the weight you hold, and how hard you press";
}

}  // namespace handshare::graphics
