#include "handshare/haptic/force_safety.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace handshare::haptic {

namespace {

void Require(bool ok, const char* field, const std::string& what) {
  if (!ok) throw std::invalid_argument(std::string("ForceSafetyConfig.") + field + ": " + what);
}

// Scales v so that |v| <= limit, keeping its direction.
Eigen::Vector3d ClampNorm(const Eigen::Vector3d& v, double limit) noexcept {
  const double n = v.norm();
  return n > limit ? Eigen::Vector3d(v * (limit / n)) : v;
}

}  // namespace

ForceSafety::ForceSafety(const ForceSafetyConfig& config) : config_(config) {
  const double period_s = config.period.count();
  const double ramp_s = config.fault_ramp_time.count();
  Require(std::isfinite(period_s) && period_s > 0.0 && period_s <= 0.1, "period",
          "must be in (0, 0.1] s, got " + std::to_string(period_s));
  Require(std::isfinite(config.max_force_N) && config.max_force_N > 0.0, "max_force_N",
          "must be > 0, got " + std::to_string(config.max_force_N));
  Require(std::isfinite(config.max_force_rate_N_per_s) && config.max_force_rate_N_per_s > 0.0,
          "max_force_rate_N_per_s", "must be > 0, got " + std::to_string(config.max_force_rate_N_per_s));
  Require(std::isfinite(ramp_s) && ramp_s >= 0.0 && ramp_s <= 10.0, "fault_ramp_time",
          "must be in [0, 10] s, got " + std::to_string(ramp_s));
  Require(std::isfinite(config.max_damping_N_s_per_m) && config.max_damping_N_s_per_m >= 0.0,
          "max_damping_N_s_per_m", "must be >= 0");
  Require(std::isfinite(config.min_speed_m_per_s) && config.min_speed_m_per_s > 0.0,
          "min_speed_m_per_s", "must be > 0");
  Require(std::isfinite(config.min_moving_speed_m_per_s) && config.min_moving_speed_m_per_s >= 0.0,
          "min_moving_speed_m_per_s", "must be >= 0");
  Require(std::isfinite(config.moving_cutoff_Hz) && config.moving_cutoff_Hz > 0.0, "moving_cutoff_Hz", "must be > 0");
  Require(config.max_position_m > 0.0, "max_position_m", "must be > 0");
  Require(config.max_speed_m_per_s > 0.0, "max_speed_m_per_s", "must be > 0");
  dt_s_ = period_s;
  moving_gain_ = 1.0 - std::exp(-2.0 * std::numbers::pi * config.moving_cutoff_Hz * period_s);
  max_step_N_ = config.max_force_rate_N_per_s * period_s;
  // The ramp reaches zero on its ramp_steps_-th faulted step: (ramp_steps_ - 1) periods after
  // the fault is seen, ramp_steps_ periods after the last healthy command. Both <= the ramp
  // time; the small slack keeps 0.02 / 0.001 from rounding up to 21.
  ramp_steps_ = static_cast<int>(std::ceil(ramp_s / period_s - 1e-9));
}

void ForceSafety::Reset() noexcept {
  fingers_ = {};
  fault_onsets_ = 0;
  rate_limited_steps_ = 0;
}

void ForceSafety::Step(const ForceSafetyInput& in, ForceSafetyOutput& out) noexcept {
  bool onset = false;
  bool limited = false;
  out.any_fault = false;
  for (int i = 0; i < kFingers; ++i) {
    const bool was_ok = fingers_[i].state == SafetyState::kOk;
    StepFinger(in.finger[i], in.device_fault, std::max(dt_s_, in.elapsed_s), fingers_[i], out.f_E_W[i],
               out.finger[i]);
    const bool faulted = out.finger[i].fault_bits != kFaultNone;
    onset = onset || (was_ok && faulted);
    limited = limited || out.finger[i].rate_limited;
    out.any_fault = out.any_fault || faulted;
  }
  if (onset) ++fault_onsets_;
  if (limited) ++rate_limited_steps_;
}

void ForceSafety::StepFinger(const FingerSafetyInput& in, bool device_fault, double elapsed_s, Finger& s,
                             Eigen::Vector3d& f_out, FingerSafetyStatus& status) noexcept {
  // Stage 1: input checks.
  std::uint8_t bits = kFaultNone;
  if (device_fault || in.fault) bits |= kFaultCaller;
  const bool p_finite = in.p_WE.allFinite();
  if (!p_finite || !in.f_desired_E_W.allFinite()) bits |= kFaultNonFinite;
  const bool p_in_range = p_finite && in.p_WE.norm() <= config_.max_position_m;
  if (p_finite && !p_in_range) bits |= kFaultOutOfRange;

  // Stage 2: passivity observer, Hannaford and Ryu (2002), "Time-domain passivity control of
  // haptic interfaces", IEEE Trans. Robotics and Automation 18(1):1-10. The finger's port
  // carries the force f on the fingertip E (from the virtual environment, VE) and E's motion.
  // The paper observes E_obs(n) = T * sum_k f(k) v(k) and calls the one-port passive while
  // E_obs >= 0. Our force is a zero-order hold: f(n-1) is applied over (t_{n-1}, t_n], so the
  // energy that left the VE over that interval is exactly f(n-1) . (p(n) - p(n-1)); we use
  // that instead of the paper's same-sample product f(n) v(n) T (a one-step-shifted estimate):
  //   W(n) = W(n-1) - f(n-1) . (p(n) - p(n-1)),   W(0) = 0,
  // W = energy into the VE port (the paper's E_obs with our sign); passive while W >= 0.
  Eigen::Vector3d v = Eigen::Vector3d::Zero();
  if (p_in_range && s.have_p_prev) {
    const Eigen::Vector3d dp = in.p_WE - s.p_prev;
    if (dp.norm() > config_.max_speed_m_per_s * elapsed_s) {
      bits |= kFaultJump;  // a jump no fingertip makes: do not count it as work
    } else {
      s.energy_J -= s.f_prev.dot(dp);
      v = dp / elapsed_s;
      s.v_moving += moving_gain_ * (v - s.v_moving);
    }
  }
  s.have_p_prev = p_in_range;
  if (p_in_range) s.p_prev = in.p_WE;

  status.fault_bits = bits;
  status.v_WE = v;
  status.damping_N_s_per_m = 0.0;
  status.rate_limited = false;

  Eigen::Vector3d f;
  if (bits != kFaultNone) {
    // Stage 5 (fault): f(k) = f0 (1 - k / N) on the k-th faulted step, k = 1..N, then zero.
    if (s.state == SafetyState::kOk) {
      s.state = SafetyState::kRampingDown;
      s.f_ramp_start = s.f_prev;
      s.ramp_step = 0;
    }
    if (s.state == SafetyState::kRampingDown) {
      ++s.ramp_step;
      const double remaining =
          ramp_steps_ > 0 ? 1.0 - static_cast<double>(s.ramp_step) / ramp_steps_ : 0.0;
      if (remaining <= 0.0) {
        s.state = SafetyState::kOff;
        f.setZero();
      } else {
        f = remaining * s.f_ramp_start;
      }
    } else {
      f.setZero();
    }
  } else {
    if (s.state != SafetyState::kOk) {
      // Back from a fault: the output restarts from where the ramp left it (the rate bound
      // below brings the force back in), and the observer keeps any debt but drops stored
      // credit, so energy absorbed before the fault cannot mask activity after it.
      s.state = SafetyState::kOk;
      s.energy_J = std::min(s.energy_J, 0.0);
    }
    // Stage 3: clamp the desired force at the device limit.
    f = ClampNorm(in.f_desired_E_W, config_.max_force_N);

    // Stage 4: passivity controller, a variable damper at the port (the paper's PC for an
    // impedance-causality VE: velocity in, force out): f = f_VE - alpha v with
    //   alpha(n) = -W_pred / (T |v(n)|^2)  if W_pred < 0, else 0,
    // where W_pred = W(n) - f_VE . v(n) T is the observed energy one step ahead if the
    // fingertip keeps its velocity (our one-step-ahead variant; the paper uses W(n) itself).
    // With this alpha, W(n) - f . v T = 0: the damper takes out exactly the predicted excess.
    // alpha is capped (a discrete damper must stay stable); any debt left over stays in W and
    // is paid on the following steps.
    if (config_.passivity) {
      const double speed2 = v.squaredNorm();
      const double moving = config_.min_moving_speed_m_per_s;
      if (speed2 > config_.min_speed_m_per_s * config_.min_speed_m_per_s &&
          s.v_moving.squaredNorm() >= moving * moving) {
        const double w_pred = s.energy_J - f.dot(v) * dt_s_;
        if (w_pred < 0.0) {
          const double alpha = std::min(-w_pred / (dt_s_ * speed2), config_.max_damping_N_s_per_m);
          f -= alpha * v;
          status.damping_N_s_per_m = alpha;
        }
      }
      f = ClampNorm(f, config_.max_force_N);
    }

    // Stage 4b: rate bound, |f(n) - f(n-1)| <= max_rate T, last so it holds for the output.
    const Eigen::Vector3d df = f - s.f_prev;
    const double dn = df.norm();
    status.rate_limited = dn > max_step_N_;
    if (status.rate_limited) f = s.f_prev + df * (max_step_N_ / dn);
  }

  s.f_prev = f;
  f_out = f;
  status.state = s.state;
  status.observed_energy_J = s.energy_J;
}

}  // namespace handshare::haptic
