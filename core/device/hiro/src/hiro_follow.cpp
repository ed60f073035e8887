#include "handshare/hiro/hiro_follow.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>

namespace handshare::hiro {

namespace {

// Scales v down to norm `limit` if it is longer (direction kept).
template <typename V>
void CapNorm(V&& v, double limit) noexcept {
  const double n = v.norm();
  if (n > limit) v *= limit / n;
}

}  // namespace

Eigen::Isometry3d FitRigid(const std::array<Eigen::Vector3d, kFingers>& a,
                           const std::array<Eigen::Vector3d, kFingers>& b,
                           const std::array<double, kFingers>& w, double* rms_m) noexcept {
  // Weighted centroids, then the rotation from the SVD of the weighted cross-covariance
  //   H = sum w (a - a_bar)(b - b_bar)^T = U S V^T,  R = V diag(1, 1, det(V U^T)) U^T
  // (Kabsch 1976; the sign fix keeps det R = +1, Umeyama 1991), t = b_bar - R a_bar.
  double w_sum = 0.0;
  Eigen::Vector3d a_bar = Eigen::Vector3d::Zero(), b_bar = Eigen::Vector3d::Zero();
  for (int i = 0; i < kFingers; ++i) {
    w_sum += w[i];
    a_bar += w[i] * a[i];
    b_bar += w[i] * b[i];
  }
  a_bar /= w_sum;
  b_bar /= w_sum;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();
  for (int i = 0; i < kFingers; ++i) H.noalias() += w[i] * (a[i] - a_bar) * (b[i] - b_bar).transpose();
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Matrix3d& U = svd.matrixU();
  const Eigen::Matrix3d& V = svd.matrixV();
  Eigen::Vector3d d(1.0, 1.0, (V * U.transpose()).determinant() < 0.0 ? -1.0 : 1.0);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = V * d.asDiagonal() * U.transpose();
  X.translation() = b_bar - X.linear() * a_bar;
  if (rms_m) {
    double s = 0.0;
    for (int i = 0; i < kFingers; ++i) s += w[i] * (X * a[i] - b[i]).squaredNorm();
    *rms_m = std::sqrt(s / w_sum);
  }
  return X;
}

Eigen::Vector3d RotationVector(const Eigen::Matrix3d& R) noexcept {
  // Through the unit quaternion (w, v): angle = 2 atan2(|v|, w), w >= 0 picks angle <= pi.
  Eigen::Quaterniond q(R);
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();
  if (s < 1e-12) return 2.0 * q.vec();  // small angle: log(R) ~ 2 v
  return (2.0 * std::atan2(s, q.w()) / s) * q.vec();
}

Twist PoseError(const Eigen::Isometry3d& X, const Eigen::Isometry3d& X_target) noexcept {
  Twist e;
  e.head<3>() = RotationVector(X_target.linear() * X.linear().transpose());
  e.tail<3>() = X_target.translation() - X.translation();
  return e;
}

ArmVector DlsJointVelocity(const ArmJacobian& J, const Twist& V, const ArmVector& qd_lo, const ArmVector& qd_hi,
                           double damping_m, double length_m) noexcept {
  // Rows in common units (m/s): rotation rows times a length.
  ArmJacobian Jw = J;
  Jw.topRows<3>() *= length_m;
  Twist rhs = V;
  rhs.head<3>() *= length_m;

  std::array<bool, kArmJoints> fixed{};
  ArmVector qd = ArmVector::Zero();
  for (int round = 0; round <= kArmJoints; ++round) {
    // Solve for the free joints with what the fixed ones leave of V.
    ArmJacobian Jf = Jw;
    Twist r = rhs;
    for (int j = 0; j < kArmJoints; ++j) {
      if (!fixed[j]) continue;
      r.noalias() -= Jw.col(j) * qd[j];
      Jf.col(j).setZero();
    }
    const Eigen::Matrix<double, 6, 6> A =
        Jf * Jf.transpose() + damping_m * damping_m * Eigen::Matrix<double, 6, 6>::Identity();
    const ArmVector qd_free = Jf.transpose() * A.ldlt().solve(r);
    // The free joint furthest beyond its bound gets fixed at it; done when none is beyond.
    int worst = -1;
    double worst_excess = 0.0;
    for (int j = 0; j < kArmJoints; ++j) {
      if (fixed[j]) continue;
      qd[j] = qd_free[j];
      const double excess = std::max(qd[j] - qd_hi[j], qd_lo[j] - qd[j]);
      if (excess > worst_excess) {
        worst_excess = excess;
        worst = j;
      }
    }
    if (worst < 0) break;
    fixed[worst] = true;
    qd[worst] = std::clamp(qd[worst], qd_lo[worst], qd_hi[worst]);
  }
  return qd.cwiseMax(qd_lo).cwiseMin(qd_hi);
}

ArmFollower::ArmFollower(const HiroModel& model) noexcept : arm_(model.arm), spec_(model.follow) {
  for (int f = 0; f < kFingers; ++f) {
    p_HE_opt_[f] = FingerFk(model.finger[f], model.finger[f].q_optimum_rad).p_HE;
  }
  const double w = 2.0 * M_PI * spec_.servo_bandwidth_Hz;
  for (int j = 0; j < kArmJoints; ++j) {
    const JointSpec& js = arm_.joint[j];
    kp_[j] = js.inertia_kg_m2 * w * w;
    kd_[j] = 2.0 * spec_.servo_damping_ratio * js.inertia_kg_m2 * w;
    leash_rad_[j] = js.max_torque_N_m / kp_[j];
  }
}

Eigen::Isometry3d ArmFollower::Target(const std::array<Eigen::Vector3d, kFingers>& p_BU,
                                      double* rms_m) const noexcept {
  // The hand pose that puts the optimum fingertips (in H) closest to the user's fingertips.
  return FitRigid(p_HE_opt_, p_BU, spec_.finger_weight, rms_m);
}

const ArmVector& ArmFollower::Step(const ArmVector& q, const ArmVector& qd, const ArmKinematics& k,
                                   const std::array<Eigen::Vector3d, kFingers>& p_HE,
                                   const std::array<Eigen::Vector3d, kFingers>& f_error_W, double dt_s,
                                   bool follow) noexcept {
  ArmFollowStatus& st = status_;
  if (!started_) {
    st.q_ref_rad = q;
    st.V_command.setZero();
    started_ = true;
  }
  ArmVector qd_ref = ArmVector::Zero();
  if (follow) {
    // 0. The user's fingertips: the device's, plus where the uncontrolled force says.
    for (int f = 0; f < kFingers; ++f) {
      Eigen::Vector3d c = -f_error_W[f] / spec_.user_finger_stiffness_N_per_m;
      if (!c.allFinite()) c.setZero();
      CapNorm(c, spec_.max_user_offset_m);
      st.p_BU[f] = k.X_BH * p_HE[f] + c;
    }
    // 1. Target: rigid fit of the optimum fingertips to the user's.
    st.X_BH_target = Target(st.p_BU, &st.fit_rms_m);
    st.error = PoseError(k.X_BH, st.X_BH_target);

    // 2. Twist towards it, capped in speed and in its change per period.
    Twist V = spec_.rate_per_s * st.error;
    CapNorm(V.head<3>(), arm_.max_hand_rate_rad_per_s);
    CapNorm(V.tail<3>(), arm_.max_hand_speed_m_per_s);
    Twist dV = V - st.V_command;
    CapNorm(dV.head<3>(), spec_.max_angular_accel_rad_per_s2 * dt_s);
    CapNorm(dV.tail<3>(), spec_.max_accel_m_per_s2 * dt_s);
    V = st.V_command + dV;

    // 3. Joint velocities: bounds go to zero at the margin inside each range (approached at
    // limit_rate), DLS within them, then all scaled into the joint speed limits.
    ArmVector lo, hi;
    for (int j = 0; j < kArmJoints; ++j) {
      const JointSpec& js = arm_.joint[j];
      lo[j] = spec_.limit_rate_per_s * (js.min_rad + spec_.limit_margin_rad - st.q_ref_rad[j]);
      hi[j] = spec_.limit_rate_per_s * (js.max_rad - spec_.limit_margin_rad - st.q_ref_rad[j]);
      // Inside the margin the bounds straddle zero; beyond it a joint may stop, not go on.
      lo[j] = std::min(lo[j], 0.0);
      hi[j] = std::max(hi[j], 0.0);
    }
    const ArmJacobian J = ArmHandJacobian(k);
    qd_ref = DlsJointVelocity(J, V, lo, hi, spec_.dls_damping_m, spec_.dls_length_m);
    double s = 1.0;
    for (int j = 0; j < kArmJoints; ++j) {
      const double a = std::abs(qd_ref[j]);
      if (a > arm_.joint[j].max_speed_rad_per_s) s = std::min(s, arm_.joint[j].max_speed_rad_per_s / a);
    }
    qd_ref *= s;
    st.V_command.noalias() = J * qd_ref;  // what the joints will deliver: the next period's start
  } else {
    st.V_command.setZero();
  }

  // 4. Reference: integrated, inside the ranges, never further from q than the servo can pull.
  st.qd_ref_rad_per_s = qd_ref;
  for (int j = 0; j < kArmJoints; ++j) {
    const JointSpec& js = arm_.joint[j];
    double r = st.q_ref_rad[j] + qd_ref[j] * dt_s;
    r = std::clamp(r, q[j] - leash_rad_[j], q[j] + leash_rad_[j]);
    st.q_ref_rad[j] = std::clamp(r, js.min_rad, js.max_rad);
  }
  st.tau_servo_N_m = kp_.cwiseProduct(st.q_ref_rad - q) + kd_.cwiseProduct(qd_ref - qd);
  return st.tau_servo_N_m;
}

}  // namespace handshare::hiro
