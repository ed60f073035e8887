#pragma once
/// Arm following: the HIRO II arm carries the haptic hand so that every finger stays near its
/// optimum pose opposite the user's fingertip while the user's hand moves and turns (the
/// chapter, 1.1-1.3: "the haptic interface follows the motion of operator's fingers").
///
/// Each control period, in the arm base frame B:
///   0. user      p_BU_i = p_BE_i - (f_meas_i - f_cmd_i) / k_user: the device fingertips sit
///                in the user's finger holders, so they are where the user's fingertips are,
///                except where a finger cannot follow (a joint at its range, a torque
///                saturated): then the force the finger failed to control pulls on the user's
///                finger, and the user's fingertip is taken that far beyond the device's (an
///                assumed finger stiffness; correction capped in length).
///   1. target    X_BH* = argmin_X sum_i w_i |X p_HEopt_i - p_BU_i|^2: the weighted
///                least-squares rigid fit (Kabsch 1976; Umeyama 1991 without scale) of the
///                optimum-pose fingertips (in H) to the user's fingertips (in B).
///   2. twist     V* = rate [log(R* R^T); p* - p], the angular and linear parts capped at the
///                hand-base speed limits (0.4 m/s, 1.4 rad/s, sourced) and their change per
///                period at the assumed accelerations: the arm follows smoothly.
///   3. joints    qd* = DLS(J_H) V* (damped least squares, Wampler 1986; rotation rows scaled by
///                a length so the rows are commensurate); a joint near its range may not move
///                further out (its velocity bound goes to zero at a margin inside the range;
///                a joint at its bound is fixed there and the rest solved again); then the
///                whole qd* is scaled so every joint is within its speed limit.
///   4. servo     q_ref += qd* dt, kept inside the ranges (less the margin) and within the
///                distance of q at which the servo saturates (no wind-up);
///                tau = Kp (q_ref - q) + Kd (qd* - qd), Kp = I w^2, Kd = 2 zeta I w per joint
///                from the drive's reflected inertia I.
/// Gravity compensation, the reaction of the fingertip forces and the limit springs are the
/// device's (HiroDevice adds them). The fingers stay force-controlled: the arm only moves their
/// bases, slowly compared with the finger force loop.
/// Everything here is noexcept and allocation-free (fixed-size Eigen).
#include <array>

#include "handshare/hiro/hiro_model.hpp"

namespace handshare::hiro {

using Twist = Eigen::Matrix<double, 6, 1>;  // [w; v], angular over linear, as the Jacobians

/// Weighted least-squares rigid transform: X minimising sum_i w_i |X a_i - b_i|^2 over proper
/// rigid transforms (det R = +1; a reflection is never returned). Weights >= 0, positive sum.
/// If rms_m is given it receives sqrt(sum_i w_i |X a_i - b_i|^2 / sum_i w_i) [m].
Eigen::Isometry3d FitRigid(const std::array<Eigen::Vector3d, kFingers>& a,
                           const std::array<Eigen::Vector3d, kFingers>& b,
                           const std::array<double, kFingers>& w, double* rms_m = nullptr) noexcept;

/// Rotation vector (unit axis times angle, angle in [0, pi]) of a rotation matrix: log(R).
Eigen::Vector3d RotationVector(const Eigen::Matrix3d& R) noexcept;

/// Error of pose X towards X_target, as a twist [log(R_t R^T); p_t - p] in the frame both are
/// expressed in [rad, m].
Twist PoseError(const Eigen::Isometry3d& X, const Eigen::Isometry3d& X_target) noexcept;

/// Joint velocities that move the hand base with twist V (in B), by damped least squares on
/// W J, W = diag(length_m I3, I3), damping damping_m [m]:
///   qd = (W J)^T ((W J)(W J)^T + damping^2 I)^-1 W V,
/// with qd_lo <= qd <= qd_hi (lo <= hi per joint): a joint whose bound is hit is fixed at it
/// and the others re-solved for what is left of V (at most kArmJoints rounds).
ArmVector DlsJointVelocity(const ArmJacobian& J, const Twist& V, const ArmVector& qd_lo, const ArmVector& qd_hi,
                           double damping_m, double length_m) noexcept;

/// What the follower did in its last Step(), for tests and telemetry.
struct ArmFollowStatus {
  Eigen::Isometry3d X_BH_target = Eigen::Isometry3d::Identity();  // the fit (step 1)
  double fit_rms_m = 0.0;                                         // its weighted rms residual
  std::array<Eigen::Vector3d, kFingers> p_BU{};               // user's fingertips (step 0)
  Twist error = Twist::Zero();                                    // PoseError(X_BH, target)
  Twist V_command = Twist::Zero();                                // capped twist (step 2)
  ArmVector q_ref_rad = ArmVector::Zero();
  ArmVector qd_ref_rad_per_s = ArmVector::Zero();
  ArmVector tau_servo_N_m = ArmVector::Zero();
};

/// The arm-following controller's state. Construct at setup; Step() once per control period.
class ArmFollower {
 public:
  /// Precomputes the optimum fingertips and the servo gains. Setup only.
  explicit ArmFollower(const HiroModel& model) noexcept;

  /// Forget the reference: the next Step() starts from the arm where it is (after a fault).
  void Reset() noexcept { started_ = false; }

  /// One control period from the measured arm joints (q, qd), their kinematics k, the device
  /// fingertips in H and each finger's force error f_meas - f_cmd (force on the user, in W =
  /// B axes) [N]. follow = false holds the arm where the reference is (no fit). Returns the
  /// servo torque [N m] (no gravity, reaction or limit terms). Real-time safe.
  const ArmVector& Step(const ArmVector& q_rad, const ArmVector& qd_rad_per_s, const ArmKinematics& k,
                        const std::array<Eigen::Vector3d, kFingers>& p_HE,
                        const std::array<Eigen::Vector3d, kFingers>& f_error_W, double dt_s,
                        bool follow) noexcept;

  const ArmFollowStatus& status() const noexcept { return status_; }
  /// Fingertips at the optimum finger pose, in H [m].
  const std::array<Eigen::Vector3d, kFingers>& p_HE_optimum() const noexcept { return p_HE_opt_; }
  /// The hand-base pose (in B) the fit asks for given the user's fingertips p_BU in B.
  /// Real-time safe.
  Eigen::Isometry3d Target(const std::array<Eigen::Vector3d, kFingers>& p_BU, double* rms_m = nullptr) const noexcept;

 private:
  ArmSpec arm_;
  ArmFollowSpec spec_;
  std::array<Eigen::Vector3d, kFingers> p_HE_opt_{};
  ArmVector kp_ = ArmVector::Zero(), kd_ = ArmVector::Zero(), leash_rad_ = ArmVector::Zero();
  bool started_ = false;
  ArmFollowStatus status_;
};

}  // namespace handshare::hiro
