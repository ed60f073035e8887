// Finger and thumb workspace volumes from the model (links of assets/devices/hiro2.json, joint
// ranges of the chapter) against the chapter's Table 1 (finger 535 cm^3, thumb 713 cm^3).
// docs/hiro.md, "Workspace volumes", gives the figures and why they differ from Table 1.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "handshare/hiro/hiro_workspace.hpp"

namespace handshare::hiro {
namespace {

constexpr double kCm3 = 1e-6;  // m^3
constexpr int kThumb = 0, kIndex = 1;

bool InRange(const JointSpec& j, double q) { return q >= j.min_rad && q <= j.max_rad; }

// The oracle: is p_F (in the finger frame F) where the fingertip is for some in-range
// posture? Closed-form inverse kinematics from the link lengths and ranges alone (not
// FingerFk): joint 1 turns the flexion plane, whose radial axis is (-sin q1, cos q1, 0);
// in that plane joints 2-3 are a two-link chain starting l1 out from joint 1.
bool Reachable(const FingerSpec& f, const Eigen::Vector3d& p_F) {
  const double l1 = f.link_m[0], l2 = f.link_m[1], l3 = f.link_m[2];
  const double rho = std::hypot(p_F.x(), p_F.y());
  for (const double sign : {1.0, -1.0}) {  // the fingertip on either side of joint 1's axis
    const double q1 = std::atan2(-sign * p_F.x(), sign * p_F.y());
    if (!InRange(f.joint[0], q1)) continue;
    const double u = sign * rho - l1, v = p_F.z();
    const double c3 = (u * u + v * v - l2 * l2 - l3 * l3) / (2.0 * l2 * l3);
    if (std::abs(c3) > 1.0) continue;
    for (const double q3 : {std::acos(c3), -std::acos(c3)}) {
      if (!InRange(f.joint[2], q3)) continue;
      const double q2 = std::atan2(v, u) - std::atan2(l3 * std::sin(q3), l2 + l3 * std::cos(q3));
      const double lo = f.joint[1].min_rad;
      if (InRange(f.joint[1], lo + std::fmod(std::fmod(q2 - lo, 2.0 * M_PI) + 2.0 * M_PI, 2.0 * M_PI))) return true;
    }
  }
  return false;
}

// Volume by counting the grid cells (edge h) whose centre is reachable: a cell cut by the
// boundary counts by its centre, so the boundary errors cancel to first order instead of
// adding (as counting every cell a swept posture touches would, by about area x h / 2).
double GridVolume(const FingerSpec& f, double h) {
  const double reach = f.link_m[0] + f.link_m[1] + f.link_m[2];
  const int n = static_cast<int>(std::ceil(reach / h));
  long count = 0;
  for (int i = -n; i < n; ++i) {
    for (int j = -n; j < n; ++j) {
      for (int k = -n; k < n; ++k) {
        count += Reachable(f, Eigen::Vector3d((i + 0.5) * h, (j + 0.5) * h, (k + 0.5) * h)) ? 1 : 0;
      }
    }
  }
  return count * h * h * h;
}

TEST(HiroWorkspace, MirrorPostureReachesTheSameFingertip) {
  const HiroModel m = HiroModel::Load(HANDSHARE_HIRO_CONFIG);
  for (const FingerSpec& f : {m.finger[kThumb], m.finger[kIndex]}) {
    for (const FingerVector& q : {FingerVector(0.2, 0.3, 0.1), FingerVector(-0.4, -0.2, -0.15),
                                  FingerVector(0.0, 1.2, 1.9)}) {
      const FingerVector q_m = MirrorFingerPosture(f, q);
      EXPECT_NEAR(q_m[2], -q[2], 1e-15);
      EXPECT_GT((q_m - q).norm(), 0.1);
      EXPECT_LT((FingerFk(f, q_m).p_HE - FingerFk(f, q).p_HE).norm(), 1e-15);
    }
  }
}

// Two independent computations agree, and are compared with Table 1. Tolerances: 1 % between
// the joint-space integral (400 x 400 nodes over joints 2-3) and the grid count (1.5 mm
// cells), each moving less than 0.05 % on a grid twice as fine (613.1 / 613.0 and
// 880.0 / 879.9 cm^3).
TEST(HiroWorkspace, FingerAndThumbVolumesAgainstTheChaptersTable1) {
  const HiroModel m = HiroModel::Load(HANDSHARE_HIRO_CONFIG);
  const double finger = FingerWorkspaceVolume(m.finger[kIndex], 4, 400);
  const double thumb = FingerWorkspaceVolume(m.finger[kThumb], 4, 400);
  const double finger_grid = GridVolume(m.finger[kIndex], 1.5e-3);
  const double thumb_grid = GridVolume(m.finger[kThumb], 1.5e-3);
  std::printf("workspace: finger %.1f cm^3 (grid %.1f; Table 1: 535), thumb %.1f cm^3 (grid %.1f; Table 1: 713)\n",
              finger / kCm3, finger_grid / kCm3, thumb / kCm3, thumb_grid / kCm3);
  EXPECT_NEAR(finger / finger_grid, 1.0, 0.01);
  EXPECT_NEAR(thumb / thumb_grid, 1.0, 0.01);
  // Every finger but the thumb has the same links and ranges.
  for (int i = 2; i < kFingers; ++i) EXPECT_NEAR(FingerWorkspaceVolume(m.finger[i], 4, 400), finger, 1e-12);

  // Table 1's ratio, 713 / 535 = 1.333, is the ratio of the joint-1 ranges (80 / 60 deg): with
  // the finger's joint-2 range (-25..94 deg) the model's thumb is exactly 4/3 of a finger.
  FingerSpec thumb_finger_joint2 = m.finger[kThumb];
  thumb_finger_joint2.joint[1] = m.finger[kIndex].joint[1];
  EXPECT_NEAR(FingerWorkspaceVolume(thumb_finger_joint2, 4, 400) / finger, 713.0 / 535.0, 0.002);

  // The links worked out from the chapter's torque/force ratios (2 / 70 / 53 mm) give more
  // than Table 1: finger 613 cm^3 (+15 %), thumb 880 cm^3 (+23 %). No links the chapter
  // allows bring both within 5 % (docs/hiro.md); these bounds hold the documented figures.
  EXPECT_NEAR(finger / kCm3, 613.0, 3.0);
  EXPECT_NEAR(thumb / kCm3, 880.0, 4.0);
}

}  // namespace
}  // namespace handshare::hiro
