#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "handshare/hiro/hiro_model.hpp"

namespace handshare::hiro {
namespace {

constexpr double kDeg = M_PI / 180.0;

const HiroModel& Model() {
  static const HiroModel m = HiroModel::Load(HANDSHARE_HIRO_CONFIG);
  return m;
}

ArmVector ArmDeg(double a, double b, double c, double d, double e, double f) {
  ArmVector q;
  q << a, b, c, d, e, f;
  return q * kDeg;
}

void ExpectNear(const Eigen::Vector3d& got, const Eigen::Vector3d& want, double tol, const char* what) {
  EXPECT_TRUE((got - want).norm() < tol) << what << ": got " << got.transpose() << ", want " << want.transpose();
}

// The hand-worked cases below use the config's lengths; check them first.
TEST(HiroKinematics, ConfigHasTheLengthsTheseCasesWereWorkedOutWith) {
  const HiroModel& m = Model();
  EXPECT_DOUBLE_EQ(m.arm.upper_arm_m, 0.30);
  EXPECT_DOUBLE_EQ(m.arm.forearm_m, 0.31);
  EXPECT_DOUBLE_EQ(m.arm.wrist_to_hand_m, 0.10);
  EXPECT_DOUBLE_EQ(m.finger[1].link_m[0], 0.002);
  EXPECT_DOUBLE_EQ(m.finger[1].link_m[1], 0.070);
  EXPECT_DOUBLE_EQ(m.finger[1].link_m[2], 0.053);
}

TEST(HiroKinematics, ArmForwardKinematicsMatchesHandWorkedPoses) {
  const ArmSpec& arm = Model().arm;
  // Zero pose: shoulder S at 0, elbow 0.30 m below, wrist 0.31 m forward, hand 0.10 m on:
  //   p_BH = (0, 0.41, -0.30), R_BH = I.
  auto k = ArmFk(arm, ArmDeg(0, 0, 0, 0, 0, 0));
  ExpectNear(k.X_BH.translation(), {0, 0.41, -0.30}, 1e-12, "zero");
  EXPECT_TRUE(k.X_BH.linear().isIdentity(1e-12));
  // Elbow -90 deg (straight arm): forearm turns about x from +y to -z:
  //   wrist (0, 0, -0.61), hand (0, 0, -0.71), R = Rx(-90).
  k = ArmFk(arm, ArmDeg(0, 0, -90, 0, 0, 0));
  ExpectNear(k.X_BH.translation(), {0, 0, -0.71}, 1e-12, "elbow -90");
  ExpectNear(k.X_BH.linear() * Eigen::Vector3d::UnitY(), {0, 0, -1}, 1e-12, "elbow -90 fingers");
  // Shoulder flexion 90 deg about x: Rx(90) (x, y, z) = (x, -z, y): (0, 0.41, -0.30) -> (0, 0.30, 0.41).
  k = ArmFk(arm, ArmDeg(90, 0, 0, 0, 0, 0));
  ExpectNear(k.X_BH.translation(), {0, 0.30, 0.41}, 1e-12, "shoulder flexion 90");
  // Abduction 90 deg about -y: (x, y, z) -> (-z, y, x): (0, 0.41, -0.30) -> (0.30, 0.41, 0);
  // the upper arm points to +x (a right arm raised sideways).
  k = ArmFk(arm, ArmDeg(0, 90, 0, 0, 0, 0));
  ExpectNear(k.X_BH.translation(), {0.30, 0.41, 0}, 1e-12, "abduction 90");
  ExpectNear(k.p_B_elbow, {0.30, 0, 0}, 1e-12, "abduction 90 elbow");
  // Wrist abduction 90 deg about z at the wrist (0, 0.31, -0.30): the 0.10 m hand offset
  // (0, 0.1, 0) turns to (-0.1, 0, 0): hand at (-0.10, 0.31, -0.30).
  k = ArmFk(arm, ArmDeg(0, 0, 0, 0, 0, 90));
  ExpectNear(k.X_BH.translation(), {-0.10, 0.31, -0.30}, 1e-12, "wrist abduction 90");
  // Pronation 90 deg then wrist flexion 90 deg: pronation turns the flexion axis from x to
  // Ry(90) x = (0, 0, -1); flexing 90 deg about -z takes the offset (0, 0.1, 0) to (0.1, 0, 0):
  // hand at (0.10, 0.31, -0.30), fingers (H's y) along +x.
  k = ArmFk(arm, ArmDeg(0, 0, 0, 90, 90, 0));
  ExpectNear(k.X_BH.translation(), {0.10, 0.31, -0.30}, 1e-12, "pronation+flexion");
  ExpectNear(k.X_BH.linear() * Eigen::Vector3d::UnitY(), {1, 0, 0}, 1e-12, "pronation+flexion fingers");
}

TEST(HiroKinematics, FingerForwardKinematicsMatchesHandWorkedPoses) {
  const FingerSpec& index = Model().finger[1];  // base (-0.036, 0, 0), links 2, 70, 53 mm
  // Straight: tip 0.125 m along y from the base.
  ExpectNear(FingerFk(index, {0, 0, 0}).p_HE, {-0.036, 0.125, 0}, 1e-12, "index straight");
  // Joint 2 at 90 deg: links 2 and 3 point up: tip (-0.036, 0.002, 0.123).
  ExpectNear(FingerFk(index, {0, 90 * kDeg, 0}).p_HE, {-0.036, 0.002, 0.123}, 1e-12, "index q2=90");
  // Joint 2 at 90, joint 3 at -90: link 2 up (70 mm), link 3 forward (53 mm):
  //   tip (-0.036, 0.002 + 0.053, 0.070).
  ExpectNear(FingerFk(index, {0, 90 * kDeg, -90 * kDeg}).p_HE, {-0.036, 0.055, 0.070}, 1e-12, "index q2=90 q3=-90");
  // Abduction 30 deg about z: tip 0.125 (-sin 30, cos 30, 0) from the base.
  ExpectNear(FingerFk(index, {30 * kDeg, 0, 0}).p_HE, {-0.036 - 0.0625, 0.125 * std::cos(30 * kDeg), 0}, 1e-12,
             "index q1=30");
  // Thumb: base (-0.081, -0.060, 0) turned -45 deg about z; straight, the tip lies
  // 0.125 (sin 45, cos 45, 0) from the base = (0.0073883, 0.0283883, 0).
  const double d = 0.125 * std::sqrt(0.5);
  ExpectNear(FingerFk(Model().finger[0], {0, 0, 0}).p_HE, {-0.081 + d, -0.060 + d, 0}, 1e-12, "thumb straight");
}

Eigen::Vector3d RotationVector(const Eigen::Matrix3d& R) {
  const Eigen::AngleAxisd aa(R);
  return aa.angle() * aa.axis();
}

template <int N>
Eigen::Matrix<double, N, 1> RandomInRange(std::mt19937& rng, const std::array<JointSpec, N>& joints) {
  Eigen::Matrix<double, N, 1> q;
  for (int i = 0; i < N; ++i) {
    // Stay 0.1 rad inside the range so the differences stay on one side of any wrap.
    std::uniform_real_distribution<double> u(joints[i].min_rad + 0.1, joints[i].max_rad - 0.1);
    q[i] = u(rng);
  }
  return q;
}

// Central differences with h = 1e-6 rad: truncation error ~ h^2 |d3 p| ~ 1e-12 m, rounding
// ~ 1e-16 / 1e-6 = 1e-10; tolerance 1e-8 leaves room for both.
constexpr double kFdStep = 1e-6, kFdTol = 1e-8;

TEST(HiroKinematics, ArmJacobiansMatchCentralDifferences) {
  const HiroModel& m = Model();
  std::mt19937 rng(7);
  for (int trial = 0; trial < 20; ++trial) {
    const ArmVector q = RandomInRange<kArmJoints>(rng, m.arm.joint);
    const ArmKinematics k = ArmFk(m.arm, q);
    const ArmJacobian J = ArmHandJacobian(k);
    const Eigen::Vector3d p_BE = k.X_BH * Eigen::Vector3d(0.02, 0.09, 0.05);  // a point on the hand
    const ArmPointJacobian Jp = ArmPointJacobianAt(k, p_BE);
    for (int i = 0; i < kArmJoints; ++i) {
      ArmVector qp = q, qm = q;
      qp[i] += kFdStep;
      qm[i] -= kFdStep;
      const ArmKinematics kp = ArmFk(m.arm, qp), km = ArmFk(m.arm, qm);
      const Eigen::Vector3d v = (kp.X_BH.translation() - km.X_BH.translation()) / (2 * kFdStep);
      const Eigen::Vector3d w = RotationVector(kp.X_BH.linear() * km.X_BH.linear().transpose()) / (2 * kFdStep);
      EXPECT_LT((J.block<3, 1>(3, i) - v).norm(), kFdTol) << "trial " << trial << " joint " << i;
      EXPECT_LT((J.block<3, 1>(0, i) - w).norm(), kFdTol) << "trial " << trial << " joint " << i;
      const Eigen::Vector3d p_local(0.02, 0.09, 0.05);
      const Eigen::Vector3d vp = (kp.X_BH * p_local - km.X_BH * p_local) / (2 * kFdStep);
      EXPECT_LT((Jp.col(i) - vp).norm(), kFdTol) << "trial " << trial << " joint " << i;
    }
  }
}

TEST(HiroKinematics, FingerJacobiansMatchCentralDifferences) {
  const HiroModel& m = Model();
  std::mt19937 rng(11);
  for (int f = 0; f < kFingers; ++f) {
    for (int trial = 0; trial < 10; ++trial) {
      const FingerVector q = RandomInRange<kFingerJoints>(rng, m.finger[f].joint);
      const FingerKinematics k = FingerFk(m.finger[f], q);
      for (int j = 0; j < kFingerJoints; ++j) {
        FingerVector qp = q, qm = q;
        qp[j] += kFdStep;
        qm[j] -= kFdStep;
        const Eigen::Vector3d v = (FingerFk(m.finger[f], qp).p_HE - FingerFk(m.finger[f], qm).p_HE) / (2 * kFdStep);
        EXPECT_LT((k.J_HE.col(j) - v).norm(), kFdTol) << "finger " << f << " joint " << j;
      }
    }
  }
}

// Gravity compensation against an independent oracle: tau = dV/dq by central differences of
// the potential energy V = sum m g z (h = 1e-6: error ~ 1e-9 N m against torques of ~10 N m).
TEST(HiroKinematics, GravityTorquesAreTheGradientOfThePotential) {
  const HiroModel& m = Model();
  std::mt19937 rng(3);
  for (int trial = 0; trial < 10; ++trial) {
    const ArmVector qa = RandomInRange<kArmJoints>(rng, m.arm.joint);
    std::array<FingerVector, kFingers> qf;
    std::array<FingerKinematics, kFingers> fk;
    for (int f = 0; f < kFingers; ++f) {
      qf[f] = RandomInRange<kFingerJoints>(rng, m.finger[f].joint);
      fk[f] = FingerFk(m.finger[f], qf[f]);
    }
    const ArmKinematics ak = ArmFk(m.arm, qa);
    const ArmVector tau = ArmGravityTorque(m, ak, fk);
    for (int i = 0; i < kArmJoints; ++i) {
      ArmVector qp = qa, qm = qa;
      qp[i] += kFdStep;
      qm[i] -= kFdStep;
      const double dV = (GravityPotential(m, ArmFk(m.arm, qp), fk) - GravityPotential(m, ArmFk(m.arm, qm), fk)) / (2 * kFdStep);
      EXPECT_NEAR(tau[i], dV, 1e-6) << "arm joint " << i;
    }
    for (int f = 0; f < kFingers; ++f) {
      const FingerVector tf = FingerGravityTorque(m.finger[f], fk[f], ak.X_BH.linear());
      for (int j = 0; j < kFingerJoints; ++j) {
        auto fp = fk, fm = fk;
        FingerVector qp = qf[f], qm = qf[f];
        qp[j] += kFdStep;
        qm[j] -= kFdStep;
        fp[f] = FingerFk(m.finger[f], qp);
        fm[f] = FingerFk(m.finger[f], qm);
        const double dV = (GravityPotential(m, ak, fp) - GravityPotential(m, ak, fm)) / (2 * kFdStep);
        EXPECT_NEAR(tf[j], dV, 1e-7) << "finger " << f << " joint " << j;
      }
    }
  }
  // And a magnitude check by hand: arm straight down (elbow -90), hand hanging: no torque at
  // the shoulder flexion joint, since every mass is on the vertical through it.
  std::array<FingerKinematics, kFingers> fk0;
  for (int f = 0; f < kFingers; ++f) fk0[f] = FingerFk(m.finger[f], FingerVector::Zero());
  const ArmVector hang = ArmGravityTorque(m, ArmFk(m.arm, ArmDeg(0, 0, -90, 0, 0, 0)), fk0);
  // Masses off the vertical: only the palm com (z offset in H = -y in B here) and fingers.
  EXPECT_LT(std::abs(hang[0]), 0.73 * kGravity_m_per_s2 * 0.2);
  // Forearm horizontal (zero pose): the elbow holds forearm (2.4 kg at 0.155 m), wrist
  // (1.5 kg at 0.31 m) and the hand (0.73 kg at about 0.31 + 0.1 + finger reach).
  const ArmVector level = ArmGravityTorque(m, ArmFk(m.arm, ArmVector::Zero()), fk0);
  const double lower = (2.4 * 0.155 + 1.5 * 0.31 + 0.73 * 0.41) * kGravity_m_per_s2;
  EXPECT_GT(std::abs(level[2]), lower);
  EXPECT_LT(std::abs(level[2]), lower + 0.73 * kGravity_m_per_s2 * 0.13);
}

}  // namespace
}  // namespace handshare::hiro
