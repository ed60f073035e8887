#pragma once
/// Hardware access for HIRO II behind one interface, so the same control code runs on the
/// simulated plant (here) and on the robot (a driver over its I/O boards, later).
///
/// Time in the simulator: Sync(t_s) integrates the plant from its last time up to t_s with
/// the motor torques of the last WriteMotorTorques() held constant (zero-order hold, as a
/// motor amplifier holds its command), in substeps of period / substeps, then latches the
/// encoders and force sensors. Nothing sleeps: a test steps 10^6 periods as fast as it can.
#include <array>
#include <memory>
#include <string_view>
#include <cstdint>
#include <optional>
#include <random>

#include "handshare/haptic/sim_hand.hpp"
#include "handshare/hiro/hiro_model.hpp"

namespace handshare::hiro {

using HandJointArray = std::array<double, kHandJoints>;  // finger f, joint j at 3 f + j
using ArmJointArray = std::array<double, kArmJoints>;

/// One 6-axis force sensor sample in its own frame S (the finger's distal link): the force
/// and moment the finger holder (the user) applies on the sensor.
struct SensorWrench {
  Eigen::Vector3d f_S_N = Eigen::Vector3d::Zero();
  Eigen::Vector3d m_S_N_m = Eigen::Vector3d::Zero();
};

class HiroHardware {
 public:
  virtual ~HiroHardware() = default;
  /// Latches encoders and sensors for the sample at t_s (the simulator integrates up to t_s).
  /// Returns false if the device cannot be read (link lost). Real-time safe.
  virtual bool Sync(double t_s) noexcept = 0;
  /// Joint angles from the encoders, as latched by Sync() [rad]. Real-time safe.
  virtual void ReadEncoders(ArmJointArray& q_arm_rad, HandJointArray& q_hand_rad) const noexcept = 0;
  /// The five 6-axis force sensors, as latched by Sync(). Real-time safe.
  virtual void ReadForceSensors(std::array<SensorWrench, kFingers>& out) const noexcept = 0;
  /// Motor torque commands at the joints [N m]; held until the next call. Real-time safe.
  virtual void WriteMotorTorques(const ArmJointArray& tau_arm_N_m, const HandJointArray& tau_hand_N_m) noexcept = 0;
  /// The node has the world `world` from t_s (haptic::Device::OnWorldReady, bridge thread).
  /// The simulated plant's scripted user hand uses it for its await_world lines; the robot
  /// has nothing to do with it. Returns true the one time it starts a script held at its start.
  virtual bool OnWorldReady(double /*t_s*/, std::string_view /*world*/) noexcept { return false; }
};

/// The simulated user's fingertip: a mass pulled by a spring-damper towards the scripted
/// fingertip (the hand's muscles), coupled to the device's finger holder by a stiffer
/// spring-damper (fingertip pulp and holder). Values are assumed, typical of the literature
/// on fingertip impedance, not measured on HIRO II.
struct UserFingerParams {
  double mass_kg = 0.03;
  double stiffness_N_per_m = 300.0;
  double damping_N_s_per_m = 2.0;
  double coupling_stiffness_N_per_m = 2000.0;
  double coupling_damping_N_s_per_m = 2.0;
};

/// A turn of the user's whole hand on top of the script (scripts move the hand without
/// turning it): the scripted fingertips turn by angle_rad about axis_W through their centroid,
/// on a minimum-jerk profile (Flash and Hogan 1985) over [t0_s, t0_s + duration_s], and stay
/// turned after. The default turns nothing.
struct UserHandTurn {
  double t0_s = 0.0;
  double duration_s = 0.0;
  Eigen::Vector3d axis_W = Eigen::Vector3d::UnitZ();  // need not be unit length; not zero
  double angle_rad = 0.0;
};

struct HiroSimOptions {
  /// The simulated user's hand; if empty, HandScript::Default around the device's reach.
  std::optional<haptic::HandScript> script;
  /// Repeat the script forever (time taken modulo its duration): for long runs and demos.
  /// The script should end where it starts.
  bool loop_script = false;
  /// Offset added to every scripted fingertip (e.g. to push into a wall) [m].
  Eigen::Vector3d p_offset_W = Eigen::Vector3d::Zero();
  /// Turn of the whole hand (applied before the offset).
  UserHandTurn turn;
  std::uint64_t seed = 1;
  double period_s = 1e-3;  // control period; the plant steps period_s / substeps
  int substeps = 5;
  int max_substeps_per_sync = 2000;  // a longer gap is skipped, not integrated (re-sync)
  bool sensor_noise = true;
  bool encoder_quantization = true;
  /// Place the arm base so that at the home pose the device fingertips meet the scripted
  /// fingertips at t = 0 (the fingers are solved to touch them); else use p_WB.
  bool place_base_at_script_start = true;
  Eigen::Vector3d p_WB = Eigen::Vector3d(0.0, -0.45, 0.45);
  UserFingerParams user;
};

/// The simulated HIRO II plant. Joint drives are independent second-order systems at the
/// joints (reflected motor inertia, viscous friction, torque and speed limits, hard stops at
/// the joint ranges); link inertia coupling is neglected (the geared motors' reflected
/// inertia is assumed to dominate), link gravity is included. The users' fingertips push on
/// the device fingertips through J^T. Kinematics are evaluated exactly at the start of each
/// Sync() and linearised within it (joints move < 0.01 rad in 1 ms).
class SimulatedHiro final : public HiroHardware {
 public:
  /// Throws ConfigError if the options are unusable. Allocates; setup only.
  SimulatedHiro(const HiroModel& model, HiroSimOptions options);

  bool Sync(double t_s) noexcept override;
  void ReadEncoders(ArmJointArray& q_arm_rad, HandJointArray& q_hand_rad) const noexcept override;
  void ReadForceSensors(std::array<SensorWrench, kFingers>& out) const noexcept override;
  void WriteMotorTorques(const ArmJointArray& tau_arm_N_m, const HandJointArray& tau_hand_N_m) noexcept override;
  /// The scripted user hand's await_world lines (haptic::ScriptClock). Any thread.
  bool OnWorldReady(double t_s, std::string_view world) noexcept override;

  // Ground truth, for tests and telemetry.
  double time_s() const noexcept { return t_s_; }
  const ArmVector& q_arm_rad() const noexcept { return q_arm_; }
  const std::array<FingerVector, kFingers>& q_finger_rad() const noexcept { return q_finger_; }
  /// Device fingertips (finger holders) in W, exact (no quantization).
  const std::array<Eigen::Vector3d, kFingers>& p_WE() const noexcept { return p_WE_; }
  /// The users' fingertips in W.
  const std::array<Eigen::Vector3d, kFingers>& p_WU() const noexcept { return p_WU_; }
  /// Force the device applies on each user fingertip [N], at the last substep.
  const std::array<Eigen::Vector3d, kFingers>& f_on_user_W() const noexcept { return f_on_user_W_; }
  /// Work the device has done on the users' fingertips since start [J].
  double energy_to_user_J() const noexcept { return energy_to_user_J_; }
  /// Torques the motors actually applied at the last substep (after saturation) [N m].
  const ArmVector& tau_arm_applied() const noexcept { return tau_arm_applied_; }
  const std::array<FingerVector, kFingers>& tau_finger_applied() const noexcept { return tau_finger_applied_; }
  const Eigen::Vector3d& p_WB() const noexcept { return p_WB_; }
  /// Syncs that skipped time instead of integrating it.
  std::uint64_t resyncs() const noexcept { return resyncs_; }

 private:
  void RefreshKinematics() noexcept;
  void Substep(double h) noexcept;
  /// The script's time at plant time t_s (non-decreasing: it passes the script's await_world
  /// holds on the way), looped if so configured.
  double ScriptTime(double t_s) const noexcept;
  /// The user's scripted fingertips at t_s: script, turn, offset.
  std::array<Eigen::Vector3d, kFingers> UserTargets(double t_s) const noexcept;

  HiroModel model_;
  HiroSimOptions options_;
  haptic::HandScript script_;
  std::unique_ptr<haptic::ScriptClock> clock_;  // the script's time (its await_world holds)
  double h_s_;
  double t_s_ = 0.0;
  Eigen::Vector3d p_WB_;

  ArmVector q_arm_ = ArmVector::Zero(), qd_arm_ = ArmVector::Zero();
  std::array<FingerVector, kFingers> q_finger_{}, qd_finger_{};
  std::array<Eigen::Vector3d, kFingers> p_WU_{}, v_WU_{}, p_target_prev_{};
  ArmVector tau_arm_cmd_ = ArmVector::Zero(), tau_arm_applied_ = ArmVector::Zero();
  std::array<FingerVector, kFingers> tau_finger_cmd_{}, tau_finger_applied_{};

  // Kinematics at the start of the current Sync() (the linearisation point).
  ArmVector q_arm0_ = ArmVector::Zero();
  std::array<FingerVector, kFingers> q_finger0_{};
  std::array<Eigen::Vector3d, kFingers> p_WE0_{};
  std::array<ArmPointJacobian, kFingers> J_arm_tip_{};
  std::array<Eigen::Matrix3d, kFingers> J_finger_W_{};
  std::array<Eigen::Matrix3d, kFingers> R_WS_{};
  ArmVector tau_gravity_arm_ = ArmVector::Zero();  // gravity's torque on the joints
  std::array<FingerVector, kFingers> tau_gravity_finger_{};

  std::array<Eigen::Vector3d, kFingers> p_WE_{}, f_on_user_W_{};
  double energy_to_user_J_ = 0.0;

  // Latched sensor values.
  ArmJointArray enc_arm_{};
  HandJointArray enc_hand_{};
  std::array<SensorWrench, kFingers> wrench_{};
  std::mt19937_64 rng_;
  std::normal_distribution<double> noise_{0.0, 1.0};
  std::uint64_t resyncs_ = 0;
};

/// Solves finger joint angles that put the fingertip at p_HE (damped least squares from
/// q_start, kept within the joint ranges). Setup and tests; returns the remaining error [m].
double SolveFingerIk(const FingerSpec& finger, const Eigen::Vector3d& p_HE, FingerVector& q_rad) noexcept;

}  // namespace handshare::hiro
