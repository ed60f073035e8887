#pragma once
/// HIRO II model: geometry, limits and masses loaded from a config file
/// (assets/devices/hiro2.json), forward kinematics, Jacobians and gravity torques of the arm
/// (6 DOF) and the five 3-DOF fingers. What the chapter gives and what is assumed is kept
/// apart in the config file; see core/device/hiro/README.md.
///
/// Frames (Drake monogram notation): W world (z up, gravity -z), B arm base at the shoulder
/// (axes parallel to W, at p_WB), H hand base, F_i base of finger i (joint 1), S_i distal link
/// of finger i (force sensor frame), E_i fingertip (centre of the finger holder).
/// Spatial Jacobians stack angular over translational rows: [w; v].
///
/// Loading may throw ConfigError; everything else here is noexcept and allocation-free.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "handshare/common/hand.hpp"

namespace handshare::hiro {

// The hand's counts are the ones every layer shares (handshare/common/hand.hpp).
using common::kArmJoints;
using common::kFingerJoints;
using common::kFingers;  // thumb, index, middle, ring, little
using common::kHandJoints;
inline constexpr double kGravity_m_per_s2 = 9.81;

using ArmVector = Eigen::Matrix<double, kArmJoints, 1>;
using ArmJacobian = Eigen::Matrix<double, 6, kArmJoints>;
using ArmPointJacobian = Eigen::Matrix<double, 3, kArmJoints>;
using FingerVector = Eigen::Vector3d;

/// The config file is missing, malformed, or a field is out of range. The message names the
/// file and the field (JSON pointer), e.g. "hiro2.json: /sourced/arm/forearm_m: ...".
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One actuated joint: range, motor limits and the drive's dynamics (reflected inertia and
/// viscous friction at the joint, after the gear).
struct JointSpec {
  double min_rad = 0.0, max_rad = 0.0;
  double max_torque_N_m = 0.0;
  double max_speed_rad_per_s = 0.0;
  double inertia_kg_m2 = 0.0;
  double viscous_N_m_s_per_rad = 0.0;
  double encoder_rad = 0.0;  // one encoder count [rad]
};

struct ArmSpec {
  /// Product-of-exponentials description at zero joint angles, in B: joint i turns about the
  /// unit axis axis_B[i] through point_B[i]; the hand base sits at p_BH0 with R_BH = I.
  std::array<Eigen::Vector3d, kArmJoints> axis_B{};
  std::array<Eigen::Vector3d, kArmJoints> point_B{};
  Eigen::Vector3d p_BH0 = Eigen::Vector3d::Zero();
  double upper_arm_m = 0.0, forearm_m = 0.0, wrist_to_hand_m = 0.0;
  std::array<JointSpec, kArmJoints> joint{};
  double upper_arm_mass_kg = 0.0, forearm_mass_kg = 0.0, wrist_mass_kg = 0.0;
  ArmVector q_home_rad = ArmVector::Zero();
  double max_hand_force_N = 0.0, max_hand_moment_N_m = 0.0;
  double max_hand_speed_m_per_s = 0.0, max_hand_rate_rad_per_s = 0.0;  // hand base, sourced
};

/// How the arm follows the user's hand (assumed; see hiro_follow.hpp for the method).
struct ArmFollowSpec {
  /// Weight of each finger in the rigid fit of the optimum fingertips to the current ones.
  std::array<double, kFingers> finger_weight{1.0, 1.0, 1.0, 1.0, 1.0};
  /// The user's fingertip is taken (f_meas - f_cmd) / this beyond the device's [N/m].
  double user_finger_stiffness_N_per_m = 300.0;
  double max_user_offset_m = 0.03;      // cap on that correction
  double rate_per_s = 5.0;              // hand-base twist = rate x pose error [1/s]
  double max_accel_m_per_s2 = 2.0;      // change of the commanded hand-base velocity
  double max_angular_accel_rad_per_s2 = 8.0;
  double dls_damping_m = 0.01;          // damped least squares, rotation rows scaled by dls_length_m
  double dls_length_m = 0.1;
  double limit_margin_rad = 0.087;      // the reference stays this far inside each joint range
  double limit_rate_per_s = 10.0;       // approach rate to that margin [1/s]
  double servo_bandwidth_Hz = 8.0;      // joint servo on the reference, per joint I w^2, 2 zeta I w
  double servo_damping_ratio = 1.0;
};

struct FingerSpec {
  Eigen::Vector3d p_HF = Eigen::Vector3d::Zero();  // joint 1 in H
  Eigen::Matrix3d R_HF = Eigen::Matrix3d::Identity();
  std::array<double, kFingerJoints> link_m{};       // joint1->joint2, joint2->joint3, joint3->tip
  std::array<double, kFingerJoints> link_mass_kg{};
  std::array<JointSpec, kFingerJoints> joint{};
  FingerVector q_optimum_rad = FingerVector::Zero();  // pose the arm keeps the finger near
};

struct HiroModel {
  ArmSpec arm;
  ArmFollowSpec follow;
  std::array<FingerSpec, kFingers> finger{};
  double palm_mass_kg = 0.0;
  Eigen::Vector3d palm_com_H = Eigen::Vector3d::Zero();
  double max_fingertip_force_N = 0.0;
  double control_rate_Hz = 0.0;
  double force_sensor_noise_N = 0.0;

  /// Reads and checks a config file. Throws ConfigError naming the file and the field.
  static HiroModel Load(const std::filesystem::path& file);
  /// Same from text; `origin` names it in error messages.
  static HiroModel Parse(const std::string& json_text, const std::string& origin);
};

/// Arm forward kinematics at q: the hand base pose and what Jacobians at other points need.
struct ArmKinematics {
  Eigen::Isometry3d X_BH = Eigen::Isometry3d::Identity();
  std::array<Eigen::Vector3d, kArmJoints> axis_B{};   // joint axes at q
  std::array<Eigen::Vector3d, kArmJoints> point_B{};  // a point on each axis at q
  Eigen::Vector3d p_B_elbow = Eigen::Vector3d::Zero();
  Eigen::Vector3d p_B_wrist = Eigen::Vector3d::Zero();
};

/// Finger forward kinematics at q, in the hand frame H.
struct FingerKinematics {
  Eigen::Vector3d p_HE = Eigen::Vector3d::Zero();          // fingertip
  Eigen::Matrix3d R_HS = Eigen::Matrix3d::Identity();      // distal link / force sensor
  Eigen::Matrix3d J_HE = Eigen::Matrix3d::Zero();          // d p_HE / d q, in H
  std::array<Eigen::Vector3d, kFingerJoints> axis_H{};
  std::array<Eigen::Vector3d, kFingerJoints> point_H{};    // joint centres
  std::array<Eigen::Vector3d, kFingerJoints> com_H{};      // link mass centres
};

ArmKinematics ArmFk(const ArmSpec& arm, const ArmVector& q_rad) noexcept;
/// Geometric Jacobian of the hand base H: [w_BH; v_BH] = J q_dot, in B.
ArmJacobian ArmHandJacobian(const ArmKinematics& k) noexcept;
/// Translational Jacobian of a point p_B rigidly moved by joints 0..joints-1 (the rest: 0).
ArmPointJacobian ArmPointJacobianAt(const ArmKinematics& k, const Eigen::Vector3d& p_B,
                                    int joints = kArmJoints) noexcept;

FingerKinematics FingerFk(const FingerSpec& finger, const FingerVector& q_rad) noexcept;

using HandWrench = Eigen::Matrix<double, 6, 1>;  // [moment; force] in B, about H's origin

/// The wrench at the hand base that arm joint torques produce: tau = J_H^T w, w = [m; f] in B
/// about H's origin (J_H from ArmHandJacobian). Least squares (SVD) where J_H is singular:
/// the part of tau that no hand-base wrench gives is held by the structure. [N m; N]
HandWrench ArmHandWrench(const ArmJacobian& J_H, const ArmVector& tau_N_m) noexcept;

/// Scales arm torques so that the hand-base wrench they produce stays within the arm's
/// output limits (the chapter: 45 N, 2.6 N m): tau *= s, s = min(1, max_force_N / |f|,
/// max_moment_N_m / |m|), so the wrench keeps its direction. Returns s.
double LimitHandWrench(const ArmJacobian& J_H, double max_force_N, double max_moment_N_m,
                       ArmVector& tau_N_m) noexcept;

/// Joint torques that hold the arm against gravity (hand and fingers included, fingers at
/// q_hand). tau = -sum_links J_com^T m g, g = (0, 0, -9.81) in B. [N m]
ArmVector ArmGravityTorque(const HiroModel& m, const ArmKinematics& arm,
                           const std::array<FingerKinematics, kFingers>& fingers) noexcept;
/// Joint torques that hold finger i against gravity, for hand orientation R_BH. [N m]
FingerVector FingerGravityTorque(const FingerSpec& finger, const FingerKinematics& k,
                                 const Eigen::Matrix3d& R_BH) noexcept;
/// Potential energy of the whole device in gravity [J] (for tests: tau_g = dV/dq).
double GravityPotential(const HiroModel& m, const ArmKinematics& arm,
                        const std::array<FingerKinematics, kFingers>& fingers) noexcept;

/// Saturates joint torques at +-max, keeping the direction of the task part where possible:
/// tau = tau_fixed + s * tau_task with the largest s in [0, 1] that keeps every joint within
/// its limit; if tau_fixed alone does not fit, each joint is clipped. Returns s (0 if clipped).
template <int N>
double SaturateTorque(const Eigen::Matrix<double, N, 1>& tau_fixed,
                      const Eigen::Matrix<double, N, 1>& tau_task,
                      const Eigen::Matrix<double, N, 1>& max_N_m,
                      Eigen::Matrix<double, N, 1>& tau_out) noexcept {
  double s = 1.0;
  bool fixed_fits = true;
  for (int i = 0; i < N; ++i) {
    const double room_hi = max_N_m[i] - tau_fixed[i], room_lo = -max_N_m[i] - tau_fixed[i];
    if (room_hi < 0.0 || room_lo > 0.0) {
      fixed_fits = false;
      continue;
    }
    if (tau_task[i] > room_hi) s = std::min(s, room_hi / tau_task[i]);
    if (tau_task[i] < room_lo) s = std::min(s, room_lo / tau_task[i]);
  }
  if (!fixed_fits) s = 0.0;
  tau_out = tau_fixed + s * tau_task;
  tau_out = tau_out.cwiseMax(-max_N_m).cwiseMin(max_N_m);
  return s;
}

}  // namespace handshare::hiro
