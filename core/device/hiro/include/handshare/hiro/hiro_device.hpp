#pragma once
/// HIRO II behind haptic::Device: reads joint angles and force sensors through HiroHardware,
/// reports the hand base and fingertips, and turns commanded fingertip forces into joint
/// torques ("redundant force control": fingers and arm together):
///   fingers  tau_f = J_f^T f_ctl + g_f(q) - D_f qd + limit springs,
///            f_ctl = f_cmd + Kp (f_cmd - f_meas) + Ki integral(f_cmd - f_meas)   (PI on the
///            force sensors, anti-windup clamp);
///   arm      tau_a = Kp (q_ref - q) + Kd (qd_ref - qd) + sum_i J_Ei^T f_cmd_i + g_a(q)
///            + limit springs: a joint servo on a reference that moves the hand base towards
///            the least-squares rigid fit of the fingers' optimum-pose fingertips to the
///            current fingertips (position and orientation; ArmFollower, hiro_follow.hpp),
///            plus the reaction of every commanded fingertip force;
///            The reaction part is scaled down so that its wrench at the hand base stays
///            within the arm's 45 N and 2.6 N m (LimitHandWrench);
///   both     saturated at the joint torque limits, the force part scaled down as a whole so
///            its direction is kept (gravity and limit terms first).
/// Read() and Command() are noexcept and allocation-free.
#include <filesystem>
#include <memory>

#include "handshare/haptic/device.hpp"
#include "handshare/hiro/hiro_follow.hpp"
#include "handshare/hiro/hiro_hardware.hpp"
#include "handshare/hiro/hiro_model.hpp"

namespace handshare::hiro {

struct HiroControlGains {
  // Tuned on the simulated plant: kp 0.5 / ki 30 sustained 1 N oscillations at rest; these
  // track a 2 N step within about 0.1 N and stay quiet (limits_test, ForceControl...).
  double force_kp = 0.2;                    // proportional gain on the force error [-]
  double force_ki_per_s = 5.0;              // integral gain [1/s]
  double force_integral_limit_N_s = 0.05;   // anti-windup bound on the integral term
  double finger_damping_N_m_s_per_rad = 0.02;
  /// Arm follows the user's hand (ArmFollower); false: the arm holds where it started.
  bool arm_following = true;
  double limit_margin_rad = 0.05;           // soft joint-limit spring starts this far inside
  double limit_stiffness_finger_N_m_per_rad = 2.0;
  double limit_stiffness_arm_N_m_per_rad = 200.0;
  double velocity_filter_Hz = 100.0;        // low-pass on encoder-difference velocities
};

/// Per-finger controller state, exposed for tests and telemetry.
struct HiroFingerStatus {
  Eigen::Vector3d f_measured_E_W = Eigen::Vector3d::Zero();  // device on user, from sensor [N]
  Eigen::Vector3d f_command_E_W = Eigen::Vector3d::Zero();
  FingerVector tau_N_m = FingerVector::Zero();               // sent to the motors
  double force_scale = 1.0;  // 1: force part fully delivered; < 1: saturated
};

class HiroDevice final : public haptic::Device {
 public:
  /// Takes the model and the hardware it drives. Allocates; setup only.
  HiroDevice(const HiroModel& model, std::unique_ptr<HiroHardware> hardware, HiroControlGains gains = {});

  haptic::DeviceCapabilities capabilities() const noexcept override;
  /// Syncs the hardware at t_s (the simulated plant integrates up to t_s here), reads
  /// encoders and sensors, computes kinematics. out.valid is false if the hardware cannot be
  /// read, a value is not finite, or a joint reads far outside its range. Real-time safe.
  void Read(double t_s, haptic::DeviceReading& out) noexcept override;
  /// Runs the force and arm controllers on the last Read() and writes motor torques. After
  /// an invalid Read() only the last good gravity torques are sent. Real-time safe.
  void Command(const std::array<Eigen::Vector3d, haptic::kFingers>& f_E_W) noexcept override;
  const char* name() const noexcept override { return "hiro"; }
  /// Passed to the hardware: the simulated plant's scripted user hand awaits worlds.
  bool OnWorldReady(double t_s, std::string_view world) noexcept override {
    return hardware_->OnWorldReady(t_s, world);
  }

  const HiroModel& model() const noexcept { return model_; }
  HiroHardware& hardware() noexcept { return *hardware_; }
  const std::array<HiroFingerStatus, kFingers>& finger_status() const noexcept { return status_; }
  const ArmVector& tau_arm_N_m() const noexcept { return tau_arm_; }
  /// The arm's torque for the reaction of the commanded fingertip forces in the last
  /// Command(), after LimitHandWrench, before joint saturation [N m].
  const ArmVector& tau_reaction_N_m() const noexcept { return tau_reaction_; }
  /// The scale LimitHandWrench put on that reaction (1: its hand-base wrench was within
  /// 45 N and 2.6 N m).
  double hand_wrench_scale() const noexcept { return hand_wrench_scale_; }
  /// The arm-following controller (its last target, error and reference).
  const ArmFollower& follower() const noexcept { return follower_; }
  const Eigen::Vector3d& p_WB() const noexcept { return p_WB_; }
  void set_p_WB(const Eigen::Vector3d& p_WB) noexcept { p_WB_ = p_WB; }

 private:
  HiroModel model_;
  std::unique_ptr<HiroHardware> hardware_;
  HiroControlGains gains_;
  Eigen::Vector3d p_WB_ = Eigen::Vector3d::Zero();

  // From the last Read().
  bool valid_ = false;
  bool have_prev_ = false;
  double t_prev_s_ = 0.0, dt_s_ = 0.0;
  ArmJointArray enc_arm_{};
  HandJointArray enc_hand_{};
  ArmVector q_arm_ = ArmVector::Zero(), qd_arm_ = ArmVector::Zero();
  std::array<FingerVector, kFingers> q_finger_{}, qd_finger_{};
  ArmKinematics arm_;
  std::array<FingerKinematics, kFingers> fingers_{};
  std::array<Eigen::Vector3d, kFingers> p_WE_{};
  std::array<SensorWrench, kFingers> wrench_{};

  // Controller state.
  ArmFollower follower_;
  std::array<Eigen::Vector3d, kFingers> force_integral_{};
  ArmVector tau_arm_ = ArmVector::Zero(), tau_gravity_arm_ = ArmVector::Zero();
  ArmVector tau_reaction_ = ArmVector::Zero();
  double hand_wrench_scale_ = 1.0;
  std::array<FingerVector, kFingers> tau_gravity_finger_{};
  std::array<HiroFingerStatus, kFingers> status_{};
};

/// The HIRO II driver on the simulated plant: loads the config, builds SimulatedHiro and the
/// device, with the arm base placed as the options say. Throws ConfigError.
std::unique_ptr<HiroDevice> MakeSimulatedHiroDevice(const std::filesystem::path& config,
                                                    const HiroSimOptions& sim,
                                                    const HiroControlGains& gains = {});

/// Same, as a haptic::Device for the node (`haptic_node --device hiro`).
std::unique_ptr<haptic::Device> MakeHiroDevice(const std::filesystem::path& config, const HiroSimOptions& sim);

}  // namespace handshare::hiro
