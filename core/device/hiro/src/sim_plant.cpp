#include <Eigen/Dense>
#include <cmath>

#include "handshare/hiro/hiro_hardware.hpp"

namespace handshare::hiro {

namespace {

// Assumed: the force sensor origin sits 20 mm proximal of the holder centre on the distal link.
const Eigen::Vector3d kSensorToHolder_S(0.0, 0.020, 0.0);

double Quantize(double q, double step) noexcept { return std::round(q / step) * step; }

// One joint drive over one substep: semi-implicit Euler on
//   I qdd = sat(tau_cmd) - b qd + tau_gravity + tau_external,
// then the motor's speed limit and the hard stops at the joint range (inelastic).
double StepJoint(const JointSpec& j, double tau_cmd, double tau_other, double h, double& q, double& qd) noexcept {
  const double tau_motor = std::clamp(tau_cmd, -j.max_torque_N_m, j.max_torque_N_m);
  const double qdd = (tau_motor - j.viscous_N_m_s_per_rad * qd + tau_other) / j.inertia_kg_m2;
  qd = std::clamp(qd + qdd * h, -j.max_speed_rad_per_s, j.max_speed_rad_per_s);
  q += qd * h;
  if (q < j.min_rad) {
    q = j.min_rad;
    qd = std::max(qd, 0.0);
  } else if (q > j.max_rad) {
    q = j.max_rad;
    qd = std::min(qd, 0.0);
  }
  return tau_motor;
}

}  // namespace

double SolveFingerIk(const FingerSpec& finger, const Eigen::Vector3d& p_HE, FingerVector& q) noexcept {
  // Damped least squares (Wampler 1986): dq = J^T (J J^T + lambda^2 I)^-1 e, clamped to range.
  constexpr double kLambda = 0.01;
  double err = 0.0;
  for (int it = 0; it < 100; ++it) {
    const FingerKinematics k = FingerFk(finger, q);
    const Eigen::Vector3d e = p_HE - k.p_HE;
    err = e.norm();
    if (err < 1e-10) break;
    const Eigen::Matrix3d A = k.J_HE * k.J_HE.transpose() + kLambda * kLambda * Eigen::Matrix3d::Identity();
    q += k.J_HE.transpose() * A.ldlt().solve(e);
    for (int j = 0; j < kFingerJoints; ++j) q[j] = std::clamp(q[j], finger.joint[j].min_rad, finger.joint[j].max_rad);
  }
  return (p_HE - FingerFk(finger, q).p_HE).norm();
}

SimulatedHiro::SimulatedHiro(const HiroModel& model, HiroSimOptions options)
    : model_(model), options_(std::move(options)), rng_(options_.seed) {
  if (!(options_.period_s > 0.0 && options_.period_s <= 0.1)) throw ConfigError("HiroSimOptions.period_s: must be in (0, 0.1]");
  if (options_.substeps < 1 || options_.substeps > 1000) throw ConfigError("HiroSimOptions.substeps: must be in [1, 1000]");
  if (options_.max_substeps_per_sync < options_.substeps) {
    throw ConfigError("HiroSimOptions.max_substeps_per_sync: must be >= substeps");
  }
  const UserFingerParams& u = options_.user;
  if (!(u.mass_kg > 0.0 && u.stiffness_N_per_m >= 0.0 && u.damping_N_s_per_m >= 0.0 &&
        u.coupling_stiffness_N_per_m > 0.0 && u.coupling_damping_N_s_per_m >= 0.0)) {
    throw ConfigError("HiroSimOptions.user: mass must be > 0, stiffnesses and dampings >= 0");
  }
  const UserHandTurn& turn = options_.turn;
  if (!(std::isfinite(turn.t0_s) && std::isfinite(turn.duration_s) && turn.duration_s >= 0.0 &&
        std::isfinite(turn.angle_rad) && turn.axis_W.allFinite() && turn.axis_W.norm() > 1e-9)) {
    throw ConfigError("HiroSimOptions.turn: times and angle must be finite, duration >= 0, axis not zero");
  }
  h_s_ = options_.period_s / options_.substeps;

  // Device at home, fingers at their optimum pose, base at the origin: where are the tips?
  q_arm_ = model_.arm.q_home_rad;
  const ArmKinematics arm = ArmFk(model_.arm, q_arm_);
  std::array<Eigen::Vector3d, kFingers> p_BE_home;
  for (int f = 0; f < kFingers; ++f) {
    q_finger_[f] = model_.finger[f].q_optimum_rad;
    p_BE_home[f] = arm.X_BH * FingerFk(model_.finger[f], q_finger_[f]).p_HE;
  }
  if (options_.script) {
    script_ = *options_.script;
  } else {
    // No script: a gentle default motion centred where the home pose puts the fingertips.
    const auto open = haptic::SimFingertips(haptic::HandPose{});
    Eigen::Vector3d mean_dev = Eigen::Vector3d::Zero(), mean_open = Eigen::Vector3d::Zero();
    for (int f = 0; f < kFingers; ++f) {
      mean_dev += p_BE_home[f] / kFingers;
      mean_open += open[f] / kFingers;
    }
    script_ = haptic::HandScript::Default(options_.p_WB + mean_dev - mean_open);
  }
  clock_ = std::make_unique<haptic::ScriptClock>(script_);
  const std::array<Eigen::Vector3d, kFingers> p_WU0 = UserTargets(0.0);
  p_WB_ = options_.p_WB;
  if (options_.place_base_at_script_start) {
    p_WB_.setZero();
    for (int f = 0; f < kFingers; ++f) p_WB_ += (p_WU0[f] - p_BE_home[f]) / kFingers;
  }
  // Each device finger starts touching its user fingertip (as far as its range allows).
  for (int f = 0; f < kFingers; ++f) {
    const Eigen::Vector3d p_HE = arm.X_BH.inverse() * (p_WU0[f] - p_WB_);
    SolveFingerIk(model_.finger[f], p_HE, q_finger_[f]);
    p_WU_[f] = p_WU0[f];
    p_target_prev_[f] = p_WU0[f];
    v_WU_[f].setZero();
    qd_finger_[f].setZero();
    tau_finger_cmd_[f].setZero();
    tau_finger_applied_[f].setZero();
  }
  RefreshKinematics();
  Sync(0.0);
}

double SimulatedHiro::ScriptTime(double t_s) const noexcept {
  // The script's own time (held at an await_world until its world is here), then the loop.
  const double script_t_s = clock_->ScriptTime(t_s);
  const double d = script_.duration_s();
  return options_.loop_script && d > 0.0 ? std::fmod(script_t_s, d) : script_t_s;
}

bool SimulatedHiro::OnWorldReady(double t_s, std::string_view world) noexcept {
  return clock_->OnWorldReady(t_s, world);
}

std::array<Eigen::Vector3d, kFingers> SimulatedHiro::UserTargets(double t_s) const noexcept {
  const auto tips = haptic::SimFingertips(script_.PoseAt(ScriptTime(t_s)));
  std::array<Eigen::Vector3d, kFingers> out;
  // Minimum-jerk fraction of the turn done by t_s: 10 s^3 - 15 s^4 + 6 s^5.
  const UserHandTurn& turn = options_.turn;
  double s = t_s >= turn.t0_s + turn.duration_s ? 1.0 : 0.0;
  if (turn.duration_s > 0.0 && t_s > turn.t0_s && t_s < turn.t0_s + turn.duration_s) {
    const double u = (t_s - turn.t0_s) / turn.duration_s;
    s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
  }
  const Eigen::Matrix3d R =
      Eigen::AngleAxisd(s * turn.angle_rad, turn.axis_W.normalized()).toRotationMatrix();
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (const auto& p : tips) c += p / kFingers;
  for (int f = 0; f < kFingers; ++f) out[f] = c + R * (tips[f] - c) + options_.p_offset_W;
  return out;
}

void SimulatedHiro::RefreshKinematics() noexcept {
  const ArmKinematics arm = ArmFk(model_.arm, q_arm_);
  std::array<FingerKinematics, kFingers> fingers;
  const Eigen::Matrix3d& R_BH = arm.X_BH.linear();
  for (int f = 0; f < kFingers; ++f) {
    fingers[f] = FingerFk(model_.finger[f], q_finger_[f]);
    const Eigen::Vector3d p_BE = arm.X_BH * fingers[f].p_HE;
    p_WE0_[f] = p_WB_ + p_BE;
    p_WE_[f] = p_WE0_[f];
    J_arm_tip_[f] = ArmPointJacobianAt(arm, p_BE);
    J_finger_W_[f] = R_BH * fingers[f].J_HE;
    R_WS_[f] = R_BH * fingers[f].R_HS;
    tau_gravity_finger_[f] = -FingerGravityTorque(model_.finger[f], fingers[f], R_BH);
    q_finger0_[f] = q_finger_[f];
  }
  tau_gravity_arm_ = -ArmGravityTorque(model_, arm, fingers);
  q_arm0_ = q_arm_;
}

void SimulatedHiro::Substep(double h) noexcept {
  const UserFingerParams& u = options_.user;
  const auto targets = UserTargets(t_s_ + h);
  ArmVector tau_ext_arm = ArmVector::Zero();
  const ArmVector dq_arm = q_arm_ - q_arm0_;
  for (int f = 0; f < kFingers; ++f) {
    // Device fingertip, linearised about the last refresh.
    const Eigen::Vector3d p_D = p_WE0_[f] + J_arm_tip_[f] * dq_arm + J_finger_W_[f] * (q_finger_[f] - q_finger0_[f]);
    const Eigen::Vector3d v_D = J_arm_tip_[f] * qd_arm_ + J_finger_W_[f] * qd_finger_[f];
    p_WE_[f] = p_D;
    // Pulp and holder: the force the user's fingertip applies on the device fingertip.
    const Eigen::Vector3d f_D = u.coupling_stiffness_N_per_m * (p_WU_[f] - p_D) +
                                u.coupling_damping_N_s_per_m * (v_WU_[f] - v_D);
    f_on_user_W_[f] = -f_D;
    tau_ext_arm.noalias() += J_arm_tip_[f].transpose() * f_D;
    const FingerVector tau_ext = J_finger_W_[f].transpose() * f_D;
    for (int j = 0; j < kFingerJoints; ++j) {
      tau_finger_applied_[f][j] = StepJoint(model_.finger[f].joint[j], tau_finger_cmd_[f][j],
                                            tau_gravity_finger_[f][j] + tau_ext[j], h, q_finger_[f][j], qd_finger_[f][j]);
    }
    // The user's fingertip: pulled to the script by the hand, pushed by the device.
    const Eigen::Vector3d& target = targets[f];
    const Eigen::Vector3d v_target = (target - p_target_prev_[f]) / h;
    p_target_prev_[f] = target;
    const Eigen::Vector3d a_U = (u.stiffness_N_per_m * (target - p_WU_[f]) +
                                 u.damping_N_s_per_m * (v_target - v_WU_[f]) - f_D) / u.mass_kg;
    v_WU_[f] += a_U * h;
    energy_to_user_J_ += f_on_user_W_[f].dot(v_WU_[f]) * h;
    p_WU_[f] += v_WU_[f] * h;
  }
  for (int j = 0; j < kArmJoints; ++j) {
    tau_arm_applied_[j] = StepJoint(model_.arm.joint[j], tau_arm_cmd_[j], tau_gravity_arm_[j] + tau_ext_arm[j], h,
                                    q_arm_[j], qd_arm_[j]);
  }
  t_s_ += h;
}

bool SimulatedHiro::Sync(double t_s) noexcept {
  if (!std::isfinite(t_s)) return false;
  long n = std::lround((t_s - t_s_) / h_s_);
  if (n > options_.max_substeps_per_sync) {
    // A long pause (debugger, overload): skip the gap rather than burst through it.
    t_s_ = t_s - options_.max_substeps_per_sync * h_s_;
    n = options_.max_substeps_per_sync;
    ++resyncs_;
  }
  for (long k = 0; k < n; ++k) {
    if (k > 0 && k % options_.substeps == 0) RefreshKinematics();
    Substep(h_s_);
  }
  if (n > 0) RefreshKinematics();

  // Latch encoders (quantized) and sensors (noisy) for this sample.
  for (int j = 0; j < kArmJoints; ++j) {
    enc_arm_[j] = options_.encoder_quantization ? Quantize(q_arm_[j], model_.arm.joint[j].encoder_rad) : q_arm_[j];
  }
  for (int f = 0; f < kFingers; ++f) {
    for (int j = 0; j < kFingerJoints; ++j) {
      const double q = q_finger_[f][j];
      enc_hand_[3 * f + j] = options_.encoder_quantization ? Quantize(q, model_.finger[f].joint[j].encoder_rad) : q;
    }
    // The sensor measures what the holder applies: minus the force on the user, in S.
    Eigen::Vector3d f_S = R_WS_[f].transpose() * (-f_on_user_W_[f]);
    if (options_.sensor_noise) {
      for (int k = 0; k < 3; ++k) f_S[k] += model_.force_sensor_noise_N * noise_(rng_);
    }
    wrench_[f].f_S_N = f_S;
    wrench_[f].m_S_N_m = kSensorToHolder_S.cross(f_S);
  }
  return true;
}

void SimulatedHiro::ReadEncoders(ArmJointArray& q_arm_rad, HandJointArray& q_hand_rad) const noexcept {
  q_arm_rad = enc_arm_;
  q_hand_rad = enc_hand_;
}

void SimulatedHiro::ReadForceSensors(std::array<SensorWrench, kFingers>& out) const noexcept { out = wrench_; }

void SimulatedHiro::WriteMotorTorques(const ArmJointArray& tau_arm_N_m, const HandJointArray& tau_hand_N_m) noexcept {
  for (int j = 0; j < kArmJoints; ++j) tau_arm_cmd_[j] = std::isfinite(tau_arm_N_m[j]) ? tau_arm_N_m[j] : 0.0;
  for (int f = 0; f < kFingers; ++f) {
    for (int j = 0; j < kFingerJoints; ++j) {
      const double t = tau_hand_N_m[3 * f + j];
      tau_finger_cmd_[f][j] = std::isfinite(t) ? t : 0.0;
    }
  }
}

}  // namespace handshare::hiro
