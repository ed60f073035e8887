#pragma once
/// Per-finger force safety for the haptic thread: the last stage between contact rendering and
/// the device. For each of the five fingers, every Step():
///   1. checks its inputs (caller's fault flags, non-finite or out-of-range data);
///   2. clamps the norm of the desired force f_E_W at max_force_N;
///   3. runs a time-domain passivity observer and controller (Hannaford and Ryu 2002) on the
///      finger's port, so energy the sampled virtual environment would create is dissipated;
///   4. bounds the rate of change: |f(n) - f(n-1)| <= max_force_rate_N_per_s * period;
///   5. on a fault, ramps the force linearly from its last value to zero within
///      fault_ramp_time, keeps it at zero while the fault lasts, and ramps back in through the
///      rate bound once it clears (never a jump).
/// Setup (constructor) validates the configuration and may throw; Step() is noexcept, never
/// allocates, locks or does I/O.
#include <Eigen/Core>
#include <array>
#include <chrono>
#include <cstdint>

#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

struct ForceSafetyConfig {
  /// Haptic loop period: Step() advances time by this much.
  std::chrono::duration<double> period{1e-3};
  /// Device limit on the fingertip force norm, per finger [N].
  double max_force_N = 3.5;
  /// Bound on the rate of change of each finger's force vector [N/s] (normal operation).
  double max_force_rate_N_per_s = 2000.0;
  /// A fault takes the force from its last value to zero within this time.
  std::chrono::duration<double> fault_ramp_time{0.02};
  /// Time-domain passivity observer and controller on or off.
  bool passivity = true;
  /// Upper bound on the passivity controller's variable damper [N s/m]. A discrete damper is
  /// itself stable only while alpha * period stays well below the fingertip's effective mass.
  double max_damping_N_s_per_m = 40.0;
  /// Below this fingertip speed the damper cannot act (alpha = -W / (T |v|^2) blows up).
  double min_speed_m_per_s = 1e-4;
  /// The damper acts only while the fingertip moves at least this fast on average (its speed
  /// low-passed at moving_cutoff_Hz). A device held still jitters (the HIRO II model on its
  /// plant ~1.3 um a step, no direction kept: a raw speed of 1-5 mm/s): with a debt in W -- a
  /// peer's press that pushed this fingertip out is energy from outside this port -- the damper
  /// turned that jitter into force noise, 0.1 N RMS on a 0.2 N press, for as long as the debt
  /// lasted (net.delayed_tail). The debt waits for real motion instead.
  double min_moving_speed_m_per_s = 0.002;
  double moving_cutoff_Hz = 20.0;
  /// A fingertip farther than this from the world origin is out-of-range data [m].
  double max_position_m = 3.0;
  /// A fingertip moving faster than this between two samples is a data glitch [m/s].
  double max_speed_m_per_s = 5.0;
};

/// What the stage is doing with one finger.
enum class SafetyState : std::uint8_t {
  kOk,          // normal: clamp, passivity, rate bound
  kRampingDown, // fault: linear ramp to zero under way
  kOff,         // fault: force held at zero
};

/// Why a finger is faulted (bit mask).
enum SafetyFault : std::uint8_t {
  kFaultNone = 0,
  kFaultCaller = 1 << 0,      // the caller's flag (device lost, stale data, ...)
  kFaultNonFinite = 1 << 1,   // NaN or Inf in the desired force or the position
  kFaultOutOfRange = 1 << 2,  // position beyond max_position_m
  kFaultJump = 1 << 3,        // moved faster than max_speed_m_per_s since the previous sample
};

/// One finger's inputs to a step.
struct FingerSafetyInput {
  Eigen::Vector3d f_desired_E_W = Eigen::Vector3d::Zero();  // from contact rendering [N]
  Eigen::Vector3d p_WE = Eigen::Vector3d::Zero();           // measured fingertip [m]
  bool fault = false;                                       // caller's per-finger fault
};

struct ForceSafetyInput {
  std::array<FingerSafetyInput, kFingers> finger{};
  bool device_fault = false;  // faults every finger (device lost, invalid reading)
  /// Time since the previous step's sample [s]; 0 or less: one period. A loop that stalled
  /// (an overloaded machine, 40 ms in CI) samples a fingertip that moved for the whole stall:
  /// that is motion, not a jump, and its speed is the distance over this interval.
  double elapsed_s = 0.0;
};

/// One finger's state after a step, for telemetry and tests.
struct FingerSafetyStatus {
  SafetyState state = SafetyState::kOk;
  std::uint8_t fault_bits = kFaultNone;  // SafetyFault mask, this step
  /// Passivity observer: energy that has flowed INTO the virtual environment port since
  /// Reset() [J]. Passive while >= 0.
  double observed_energy_J = 0.0;
  double damping_N_s_per_m = 0.0;           // passivity controller's alpha, this step
  Eigen::Vector3d v_WE = Eigen::Vector3d::Zero();  // backward-difference velocity [m/s]
  /// The rate bound cut this step's change: the force asked for moved faster than
  /// max_force_rate_N_per_s (a step in what the world renders, or the ramp back after a fault).
  bool rate_limited = false;
};

struct ForceSafetyOutput {
  std::array<Eigen::Vector3d, kFingers> f_E_W{};  // force to command [N]
  std::array<FingerSafetyStatus, kFingers> finger{};
  bool any_fault = false;
};

class ForceSafety {
 public:
  /// Throws std::invalid_argument naming the field if the configuration is not usable.
  explicit ForceSafety(const ForceSafetyConfig& config);

  /// One haptic step: inputs at sample n, output to hold until sample n+1. Real-time safe.
  void Step(const ForceSafetyInput& in, ForceSafetyOutput& out) noexcept;

  /// Back to the initial state: zero force, zero observed energy, no fault. Not real-time.
  void Reset() noexcept;

  const ForceSafetyConfig& config() const noexcept { return config_; }
  /// Steps that began a fault (any finger), since construction.
  std::uint64_t fault_onsets() const noexcept { return fault_onsets_; }
  /// Steps in which the rate bound cut any finger's change, since construction.
  std::uint64_t rate_limited_steps() const noexcept { return rate_limited_steps_; }

 private:
  struct Finger {
    Eigen::Vector3d f_prev = Eigen::Vector3d::Zero();  // output of the previous step
    Eigen::Vector3d p_prev = Eigen::Vector3d::Zero();
    bool have_p_prev = false;
    double energy_J = 0.0;  // observer W(n)
    Eigen::Vector3d v_moving = Eigen::Vector3d::Zero();  // speed low-passed (min_moving_speed)
    SafetyState state = SafetyState::kOk;
    Eigen::Vector3d f_ramp_start = Eigen::Vector3d::Zero();
    int ramp_step = 0;
  };
  void StepFinger(const FingerSafetyInput& in, bool device_fault, double elapsed_s, Finger& s,
                  Eigen::Vector3d& f_out, FingerSafetyStatus& status) noexcept;

  ForceSafetyConfig config_;
  double dt_s_;
  double max_step_N_;  // max_force_rate * period
  int ramp_steps_;     // ceil(fault_ramp_time / period)
  double moving_gain_; // the low-pass's 1 - exp(-2 pi f_c T)
  std::array<Finger, kFingers> fingers_{};
  std::uint64_t fault_onsets_ = 0;
  std::uint64_t rate_limited_steps_ = 0;
};

}  // namespace handshare::haptic
