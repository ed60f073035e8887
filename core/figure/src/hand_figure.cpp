#include "handshare/figure/hand_figure.hpp"

#include <cmath>
#include <numbers>

#include "handshare/contact/finger_contact.hpp"  // contact::ToPose
#include "handshare/hiro/hiro_model.hpp"

namespace handshare::figure {

namespace {

constexpr double kMaxFlexRad = 2.0 * std::numbers::pi / 3.0;  // per joint: a fist
constexpr double kLinkHalfWidthM = 0.007;
constexpr double kJointRadiusM = 0.0075;
constexpr double kStylusLengthM = 0.12;    // a pen or a gripper handle, as drawn
constexpr double kStylusHalfWidthM = 0.005;
constexpr double kGripperHandleM = 0.04;   // the handle sits this far above the points' centre

// The planar chain of `links` with every joint flexed by `theta`: its end point.
Eigen::Vector2d ChainEnd(const std::array<double, 3>& links, double theta) {
  Eigen::Vector2d p = Eigen::Vector2d::Zero();
  for (int k = 0; k < 3; ++k) p += links[k] * Eigen::Vector2d(std::cos(k * theta), std::sin(k * theta));
  return p;
}

}  // namespace

const std::array<std::array<double, 3>, kFingers>& HandLinkLengths() noexcept {
  static const std::array<std::array<double, 3>, kFingers> kLinks = {{
      {0.035, 0.030, 0.024},   // thumb: metacarpal, proximal, distal
      {0.035, 0.022, 0.018},   // index: proximal, middle, distal phalanx
      {0.038, 0.024, 0.018},   // middle
      {0.035, 0.023, 0.018},   // ring
      {0.030, 0.019, 0.017}}};  // little
  return kLinks;
}

const std::array<Eigen::Vector3d, kFingers>& HandKnuckles_H() noexcept {
  // The simulated hand's frame (haptic_node's sim_hand): fingers along +y, thumb towards -x.
  static const std::array<Eigen::Vector3d, kFingers> kKnuckles = {
      Eigen::Vector3d(-0.030, -0.010, -0.010), Eigen::Vector3d(-0.030, 0.030, 0.0),
      Eigen::Vector3d(-0.010, 0.032, 0.0), Eigen::Vector3d(0.010, 0.030, 0.0),
      Eigen::Vector3d(0.028, 0.026, 0.0)};
  return kKnuckles;
}

HandFigure FitHandToFingertips(const Eigen::Isometry3d& X_WH, const std::array<Eigen::Vector3d, kFingers>& p_WE) {
  HandFigure hand;
  hand.X_WH = X_WH.matrix().allFinite() ? X_WH : Eigen::Isometry3d::Identity();
  const Eigen::Vector3d palm_normal_W = -(hand.X_WH.linear() * Eigen::Vector3d::UnitZ());  // the palm side
  for (int f = 0; f < kFingers; ++f) {
    const std::array<double, 3>& links = HandLinkLengths()[f];
    const double length = links[0] + links[1] + links[2];
    const Eigen::Vector3d knuckle = hand.X_WH * HandKnuckles_H()[f];
    auto& joints = hand.joints_W[f];
    joints[0] = knuckle;
    Eigen::Vector3d chord = p_WE[f] - knuckle;
    const double d = chord.norm();
    if (!chord.allFinite() || d < 1e-9) {  // no usable fingertip: a straight finger along +y
      const Eigen::Vector3d along = hand.X_WH.linear() * Eigen::Vector3d::UnitY();
      double s = 0.0;
      for (int k = 0; k < 3; ++k) joints[k + 1] = knuckle + (s += links[k]) * along;
      continue;
    }
    const Eigen::Vector3d u = chord / d;
    // The bending direction: the palm's normal, made orthogonal to the chord (or any
    // orthogonal direction where the two are parallel).
    Eigen::Vector3d n = palm_normal_W - palm_normal_W.dot(u) * u;
    if (n.norm() < 1e-6) n = u.unitOrthogonal();
    n.normalize();
    // Equal flexion theta at each joint whose chain spans exactly d (the span falls as theta
    // grows over [0, kMaxFlex]); beyond reach: straight and stretched.
    double theta = 0.0;
    double scale = 1.0;
    if (d >= length) {
      scale = d / length;
      hand.stretched[f] = d > length * (1.0 + 1e-9);
    } else {
      double lo = 0.0, hi = kMaxFlexRad;
      if (ChainEnd(links, hi).norm() >= d) {
        theta = hi;  // closer than a fist reaches: as bent as a finger goes, and scaled down
        scale = d / ChainEnd(links, hi).norm();
      } else {
        for (int it = 0; it < 60; ++it) {
          const double mid = 0.5 * (lo + hi);
          (ChainEnd(links, mid).norm() > d ? lo : hi) = mid;
        }
        theta = 0.5 * (lo + hi);
      }
    }
    // The planar chain, rotated so that its chord lies along u, placed in the (u, n) plane: it
    // curls towards n, the palm, and its knuckles bulge away from it.
    const Eigen::Vector2d end = ChainEnd(links, theta);
    const double phi = std::atan2(end.y(), end.x());
    const Eigen::Rotation2Dd to_chord(-phi);
    Eigen::Vector2d p = Eigen::Vector2d::Zero();
    for (int k = 0; k < 3; ++k) {
      p += links[k] * Eigen::Vector2d(std::cos(k * theta), std::sin(k * theta));
      const Eigen::Vector2d q = scale * (to_chord * p);
      joints[k + 1] = knuckle + q.x() * u + q.y() * n;
    }
    joints[3] = p_WE[f];  // exact, not within round-off
  }
  return hand;
}

namespace {
/// A thin box from a to b (nothing when they meet).
void AddLink(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double half_width_m, HandParts& parts) {
  const double length = (b - a).norm();
  if (!(length > 1e-6)) return;
  parts.boxes.push_back(Box{0.5 * (a + b), Eigen::Vector3d(half_width_m, 0.5 * length, half_width_m),
                            Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitY(), (b - a) / length)});
}

/// A link from a towards a fingertip at b that stops at the fingertip sphere's surface (none
/// when a is inside the sphere).
void AddLinkToFingertip(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double fingertip_radius_m,
                        double half_width_m, HandParts& parts) {
  const double full = (b - a).norm();
  if (!(full > fingertip_radius_m)) return;
  AddLink(a, a + (b - a) * ((full - fingertip_radius_m) / full), half_width_m, parts);
}
}  // namespace

void AddHandFigure(const HandFigure& hand, double fingertip_radius_m, HandParts& parts) {
  parts.boxes.push_back(Box{hand.X_WH * hand.palm_center_H, hand.palm_half_extents_H, Eigen::Quaterniond(hand.X_WH.linear())});
  for (const auto& joints : hand.joints_W) {
    AddLink(joints[0], joints[1], kLinkHalfWidthM, parts);
    AddLink(joints[1], joints[2], kLinkHalfWidthM, parts);
    AddLinkToFingertip(joints[2], joints[3], fingertip_radius_m, kLinkHalfWidthM, parts);
    for (int k = 0; k < 3; ++k) parts.spheres.push_back(Sphere{joints[k], kJointRadiusM});
  }
}


void AddDeviceFigure(const std::array<Eigen::Vector3d, kFingers>& p_WE, unsigned present, double fingertip_radius_m,
                     HandParts& parts) {
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int n = 0;
  for (int f = 0; f < kFingers; ++f) {
    if (((present >> f) & 1u) == 0 || !p_WE[f].allFinite()) continue;
    centre += p_WE[f];
    ++n;
  }
  if (n == 0) return;
  centre /= n;
  // Up and towards the user (-y): how a pen or a gripper's handle is held over a table.
  const Eigen::Vector3d up = Eigen::Vector3d(0.0, -0.45, 1.0).normalized();
  if (n == 1) {
    AddLink(centre + fingertip_radius_m * up, centre + (fingertip_radius_m + kStylusLengthM) * up, kStylusHalfWidthM, parts);
    return;
  }
  const Eigen::Vector3d handle = centre + kGripperHandleM * up;
  AddLink(handle, handle + kStylusLengthM * up, kStylusHalfWidthM, parts);
  for (int f = 0; f < kFingers; ++f) {
    if (((present >> f) & 1u) == 0 || !p_WE[f].allFinite()) continue;
    AddLinkToFingertip(handle, p_WE[f], fingertip_radius_m, kLinkHalfWidthM, parts);
  }
}

HandFigure HiroHandFigure(const hiro::HiroModel& model, const Eigen::Isometry3d& X_WH,
                          const std::array<double, common::kHandJoints>& q_hand_rad) {
  static_assert(common::kFingerJoints == hiro::FingerVector::RowsAtCompileTime);
  HandFigure hand;
  hand.X_WH = X_WH;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = Eigen::Vector3d::Constant(-1e9);
  for (int f = 0; f < kFingers; ++f) {
    hiro::FingerVector q;
    for (int j = 0; j < common::kFingerJoints; ++j) {
      const double q_j = q_hand_rad[common::kFingerJoints * f + j];
      q[j] = std::isfinite(q_j) ? q_j : 0.0;
    }
    const hiro::FingerKinematics k = hiro::FingerFk(model.finger[f], q);
    for (int j = 0; j < 3; ++j) hand.joints_W[f][j] = X_WH * k.point_H[j];
    hand.joints_W[f][3] = X_WH * k.p_HE;
    lo = lo.cwiseMin(model.finger[f].p_HF);
    hi = hi.cwiseMax(model.finger[f].p_HF);
  }
  hand.palm_center_H = 0.5 * (lo + hi);
  hand.palm_half_extents_H = (0.5 * (hi - lo) + Eigen::Vector3d::Constant(0.010)).cwiseMax(0.008);
  return hand;
}

Eigen::Isometry3d HandBasePose(const std::array<double, 3>& p_WH_m, const std::array<double, 4>& q_WH_wxyz) noexcept {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  if (!contact::ToPose(p_WH_m, q_WH_wxyz, X)) X.translation() = Eigen::Vector3d(p_WH_m[0], p_WH_m[1], p_WH_m[2]);
  return X;
}

HandParts DrawnHand(const DeviceHand& hand, const hiro::HiroModel* hiro_model) {
  HandParts parts;
  parts.rgb = kSkinRgb;
  const unsigned present = ~hand.absent_fingers & ((1u << kFingers) - 1u);
  if (present != (1u << kFingers) - 1u) {
    // A stylus or a gripper (a device with fewer fingers): what the user really holds.
    AddDeviceFigure(hand.p_WE, present, hand.fingertip_radius_m, parts);
  } else if (hiro_model != nullptr && hand.hiro) {
    parts.rgb = kHiroRgb;
    AddHandFigure(HiroHandFigure(*hiro_model, HandBasePose(hand.p_WH_m, hand.q_WH_wxyz), hand.q_hand_rad),
                  hand.fingertip_radius_m, parts);
  } else {
    AddHandFigure(FitHandToFingertips(HandBasePose(hand.p_WH_m, hand.q_WH_wxyz), hand.p_WE), hand.fingertip_radius_m,
                  parts);
  }
  return parts;
}

}  // namespace handshare::figure
