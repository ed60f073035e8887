#include "handshare/hiro/hiro_device.hpp"

#include <cmath>

#include "handshare/common/clock.hpp"

namespace handshare::hiro {

namespace {

constexpr double kRangeTolerance_rad = 0.1;  // a reading this far outside a range is bad data

// Soft joint limit: a spring pushing back once q is within `margin` of either end.
double LimitTorque(const JointSpec& j, double q, double margin, double stiffness) noexcept {
  if (q < j.min_rad + margin) return stiffness * (j.min_rad + margin - q);
  if (q > j.max_rad - margin) return stiffness * (j.max_rad - margin - q);
  return 0.0;
}

Eigen::Vector3d ClampNorm(const Eigen::Vector3d& v, double limit) noexcept {
  const double n = v.norm();
  return n > limit ? Eigen::Vector3d(v * (limit / n)) : v;
}

}  // namespace

HiroDevice::HiroDevice(const HiroModel& model, std::unique_ptr<HiroHardware> hardware, HiroControlGains gains)
    : model_(model), hardware_(std::move(hardware)), gains_(gains), follower_(model_) {
  if (!hardware_) throw ConfigError("HiroDevice: no hardware");
  for (auto& i : force_integral_) i.setZero();
  for (auto& t : tau_gravity_finger_) t.setZero();
  for (int f = 0; f < kFingers; ++f) {
    q_finger_[f].setZero();
    qd_finger_[f].setZero();
  }
}

haptic::DeviceCapabilities HiroDevice::capabilities() const noexcept {
  haptic::DeviceCapabilities c;
  c.fingers = kFingers;
  c.max_fingertip_force_N = model_.max_fingertip_force_N;
  c.max_force_rate_N_per_s = 2000.0;
  c.control_rate_Hz = model_.control_rate_Hz;
  c.hand_joints = kHandJoints;
  c.arm_joints = kArmJoints;
  return c;
}

void HiroDevice::Read(double t_s, haptic::DeviceReading& out) noexcept {
  bool ok = hardware_->Sync(t_s);
  hardware_->ReadEncoders(enc_arm_, enc_hand_);
  hardware_->ReadForceSensors(wrench_);

  // Joint angles; velocities from encoder differences through a first-order low-pass.
  ArmVector q_arm;
  std::array<FingerVector, kFingers> q_finger;
  for (int j = 0; j < kArmJoints; ++j) {
    q_arm[j] = enc_arm_[j];
    const JointSpec& js = model_.arm.joint[j];
    ok = ok && std::isfinite(q_arm[j]) && q_arm[j] > js.min_rad - kRangeTolerance_rad &&
         q_arm[j] < js.max_rad + kRangeTolerance_rad;
  }
  for (int f = 0; f < kFingers; ++f) {
    for (int j = 0; j < kFingerJoints; ++j) {
      q_finger[f][j] = enc_hand_[3 * f + j];
      const JointSpec& js = model_.finger[f].joint[j];
      ok = ok && std::isfinite(q_finger[f][j]) && q_finger[f][j] > js.min_rad - kRangeTolerance_rad &&
           q_finger[f][j] < js.max_rad + kRangeTolerance_rad;
    }
    ok = ok && wrench_[f].f_S_N.allFinite();
  }
  ok = ok && std::isfinite(t_s);
  dt_s_ = 1.0 / model_.control_rate_Hz;
  if (ok) {
    if (have_prev_ && t_s > t_prev_s_) {
      dt_s_ = t_s - t_prev_s_;
      const double a = dt_s_ / (dt_s_ + 1.0 / (2.0 * M_PI * gains_.velocity_filter_Hz));
      qd_arm_ += a * ((q_arm - q_arm_) / dt_s_ - qd_arm_);
      for (int f = 0; f < kFingers; ++f) qd_finger_[f] += a * ((q_finger[f] - q_finger_[f]) / dt_s_ - qd_finger_[f]);
    }
    q_arm_ = q_arm;
    q_finger_ = q_finger;
    t_prev_s_ = t_s;
    have_prev_ = true;

    arm_ = ArmFk(model_.arm, q_arm_);
    const Eigen::Matrix3d& R_BH = arm_.X_BH.linear();
    for (int f = 0; f < kFingers; ++f) {
      fingers_[f] = FingerFk(model_.finger[f], q_finger_[f]);
      p_WE_[f] = p_WB_ + arm_.X_BH * fingers_[f].p_HE;
      // The sensor measures what the holder applies on the device; the user feels minus that.
      status_[f].f_measured_E_W = -(R_BH * fingers_[f].R_HS * wrench_[f].f_S_N);
      tau_gravity_finger_[f] = FingerGravityTorque(model_.finger[f], fingers_[f], R_BH);
    }
    tau_gravity_arm_ = ArmGravityTorque(model_, arm_, fingers_);
  }
  valid_ = ok;

  out.stamp_ns = common::SteadyNowNs();
  out.valid = ok;
  out.p_WH = p_WB_ + arm_.X_BH.translation();
  const Eigen::Quaterniond q_WH(arm_.X_BH.linear());
  out.q_WH_wxyz = Eigen::Vector4d(q_WH.w(), q_WH.x(), q_WH.y(), q_WH.z());
  for (int f = 0; f < kFingers; ++f) out.p_WE[f] = p_WE_[f];
  for (int j = 0; j < kArmJoints; ++j) out.q_arm_rad[j] = enc_arm_[j];
  for (int j = 0; j < kHandJoints; ++j) out.q_hand_rad[j] = enc_hand_[j];
}

void HiroDevice::Command(const std::array<Eigen::Vector3d, haptic::kFingers>& f_E_W) noexcept {
  HandJointArray tau_hand{};
  ArmJointArray tau_arm{};
  if (!valid_) {
    // No trustworthy state: hold the device up with the last good gravity torques, no force.
    for (int f = 0; f < kFingers; ++f) {
      force_integral_[f].setZero();
      for (int j = 0; j < kFingerJoints; ++j) tau_hand[3 * f + j] = tau_gravity_finger_[f][j];
    }
    for (int j = 0; j < kArmJoints; ++j) tau_arm[j] = tau_gravity_arm_[j];
    follower_.Reset();  // on recovery the arm's reference starts again where the arm is
    hardware_->WriteMotorTorques(tau_arm, tau_hand);
    return;
  }
  const Eigen::Matrix3d& R_BH = arm_.X_BH.linear();
  const double g = gains_.limit_margin_rad;

  // Fingers: PI force control on the sensors, J^T to joints, gravity and limits first.
  ArmVector tau_reaction = ArmVector::Zero();
  std::array<Eigen::Vector3d, kFingers> p_HE, f_error_W;
  for (int f = 0; f < kFingers; ++f) {
    const FingerSpec& spec = model_.finger[f];
    HiroFingerStatus& st = status_[f];
    const Eigen::Vector3d f_cmd =
        f_E_W[f].allFinite() ? ClampNorm(f_E_W[f], model_.max_fingertip_force_N) : Eigen::Vector3d::Zero();
    const Eigen::Vector3d e = f_cmd - st.f_measured_E_W;
    const double lim = gains_.force_integral_limit_N_s;
    force_integral_[f] = (force_integral_[f] + e * dt_s_).cwiseMax(-lim).cwiseMin(lim);
    const Eigen::Vector3d f_ctl = f_cmd + gains_.force_kp * e + gains_.force_ki_per_s * force_integral_[f];

    const Eigen::Matrix3d J_W = R_BH * fingers_[f].J_HE;
    const FingerVector tau_task = J_W.transpose() * f_ctl;
    FingerVector tau_fixed = tau_gravity_finger_[f] - gains_.finger_damping_N_m_s_per_rad * qd_finger_[f];
    FingerVector tau_max;
    for (int j = 0; j < kFingerJoints; ++j) {
      tau_fixed[j] += LimitTorque(spec.joint[j], q_finger_[f][j], g, gains_.limit_stiffness_finger_N_m_per_rad);
      tau_max[j] = spec.joint[j].max_torque_N_m;
    }
    st.force_scale = SaturateTorque<3>(tau_fixed, tau_task, tau_max, st.tau_N_m);
    st.f_command_E_W = f_cmd;
    for (int j = 0; j < kFingerJoints; ++j) tau_hand[3 * f + j] = st.tau_N_m[j];

    // The arm carries the reaction of the commanded force at this fingertip.
    const Eigen::Vector3d p_BE = arm_.X_BH * fingers_[f].p_HE;
    tau_reaction.noalias() += ArmPointJacobianAt(arm_, p_BE).transpose() * f_cmd;
    p_HE[f] = fingers_[f].p_HE;
    f_error_W[f] = -e;
  }

  // Arm: the servo that carries the hand to where every finger is near its optimum pose
  // (hiro_follow.hpp), plus the reaction of the fingertip forces; gravity and limits first.
  const ArmVector& tau_servo = follower_.Step(q_arm_, qd_arm_, arm_, p_HE, f_error_W, dt_s_, gains_.arm_following);
  // What the fingertip forces ask of the arm at the hand base is at most the chapter's 45 N
  // and 2.6 N m: the reaction is scaled down as a whole (direction kept). The servo that
  // carries the arm after the user's hand is left alone: most of its torque accelerates the
  // arm's own drives, and it is bounded by the joint torque and speed limits.
  hand_wrench_scale_ = LimitHandWrench(ArmHandJacobian(arm_), model_.arm.max_hand_force_N,
                                       model_.arm.max_hand_moment_N_m, tau_reaction);
  tau_reaction_ = tau_reaction;
  const ArmVector tau_task = tau_servo + tau_reaction;
  ArmVector tau_fixed = tau_gravity_arm_;
  ArmVector tau_max;
  for (int j = 0; j < kArmJoints; ++j) {
    tau_fixed[j] += LimitTorque(model_.arm.joint[j], q_arm_[j], g, gains_.limit_stiffness_arm_N_m_per_rad);
    tau_max[j] = model_.arm.joint[j].max_torque_N_m;
  }
  SaturateTorque<kArmJoints>(tau_fixed, tau_task, tau_max, tau_arm_);
  for (int j = 0; j < kArmJoints; ++j) tau_arm[j] = tau_arm_[j];
  hardware_->WriteMotorTorques(tau_arm, tau_hand);
}

std::unique_ptr<HiroDevice> MakeSimulatedHiroDevice(const std::filesystem::path& config, const HiroSimOptions& sim,
                                                    const HiroControlGains& gains) {
  const HiroModel model = HiroModel::Load(config);
  auto plant = std::make_unique<SimulatedHiro>(model, sim);
  const Eigen::Vector3d p_WB = plant->p_WB();
  auto device = std::make_unique<HiroDevice>(model, std::move(plant), gains);
  device->set_p_WB(p_WB);
  return device;
}

std::unique_ptr<haptic::Device> MakeHiroDevice(const std::filesystem::path& config, const HiroSimOptions& sim) {
  return MakeSimulatedHiroDevice(config, sim);
}

}  // namespace handshare::hiro
