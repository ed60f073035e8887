#pragma once
/// A user's hand as the screens draw it: a palm and five fingers of three links each, fitted to
/// the device's hand base and fingertips (what every device reports), a HIRO II's own hand from
/// its joint angles, or what a user with fewer fingers holds (a pen, a gripper). Plain data: the
/// graphics node draws the parts with OpenGL (graphics/hand_figure.hpp), the web console sends
/// them to its view (docs/web_console.md), so both draw one figure by one rule.
#include <array>
#include <vector>

#include <Eigen/Geometry>

#include "handshare/common/hand.hpp"

namespace handshare::hiro {
struct HiroModel;
}

namespace handshare::figure {

/// Fingers thumb first, as the device state's fingertips.
using common::kFingers;

struct HandFigure {
  Eigen::Isometry3d X_WH = Eigen::Isometry3d::Identity();  ///< the palm's frame: fingers along +y, palm facing -z
  /// Per finger: its knuckle (the thumb's base joint), two inner joints and its fingertip, in W.
  std::array<std::array<Eigen::Vector3d, 4>, kFingers> joints_W{};
  /// Per finger: true if the fingertip was farther from its knuckle than the finger is long (the
  /// links were stretched to reach it).
  std::array<bool, kFingers> stretched{};
  /// The palm, a box in H: its centre and half sizes along H's axes.
  Eigen::Vector3d palm_center_H{0.0, 0.0, -0.004};  // its front edge at the knuckles
  Eigen::Vector3d palm_half_extents_H{0.040, 0.030, 0.008};
};

/// The link lengths of each finger [m], knuckle to fingertip, thumb first (an adult hand).
[[nodiscard]] const std::array<std::array<double, 3>, kFingers>& HandLinkLengths() noexcept;
/// Where each knuckle sits on the palm, in H [m].
[[nodiscard]] const std::array<Eigen::Vector3d, kFingers>& HandKnuckles_H() noexcept;

/// Fits the hand to a hand base X_WH and five fingertips p_WE: each finger bends equally at its
/// three joints, towards the palm, in the plane of its knuckle, its fingertip and the palm's
/// normal, so that its last link ends exactly at the fingertip; a fingertip beyond reach
/// straightens the finger and stretches it. Non-finite input gives a hand at X_WH, fingers straight.
[[nodiscard]] HandFigure FitHandToFingertips(const Eigen::Isometry3d& X_WH,
                                             const std::array<Eigen::Vector3d, kFingers>& p_WE);

/// The HIRO II's own hand at its joint angles (DeviceState::q_hand_rad, finger f joint j at
/// 3 f + j), through the model's finger kinematics (hiro::FingerFk) from its hand base X_WH:
/// each finger's three joint centres and its fingertip; the palm spans the fingers' bases.
[[nodiscard]] HandFigure HiroHandFigure(const hiro::HiroModel& model, const Eigen::Isometry3d& X_WH,
                                        const std::array<double, common::kHandJoints>& q_hand_rad);

/// The hand base pose of a device state's p_WH_m and q_WH_wxyz: its quaternion normalized, the
/// identity rotation where the quaternion is unusable (not finite, |q| <= 0.5).
[[nodiscard]] Eigen::Isometry3d HandBasePose(const std::array<double, 3>& p_WH_m,
                                             const std::array<double, 4>& q_WH_wxyz) noexcept;

/// A box B of a drawn hand: its centre in W, half sizes along B's axes, B's orientation in W.
struct Box {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d half_extents_m = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_WB = Eigen::Quaterniond::Identity();
};
/// A sphere of a drawn hand (a joint): its centre in W and radius.
struct Sphere {
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  double radius_m = 0.0;
};

/// A drawn hand: its boxes, then its spheres, all of one colour (linear RGB, 0-1), drawn in that
/// order over the scene (hidden by objects in front of them, writing no depth, so that the
/// fingertips, drawn after them as markers, show through). The fingertips are not parts: the
/// caller draws them in the fingers' colours.
struct HandParts {
  std::array<float, 3> rgb{1.0F, 1.0F, 1.0F};
  std::vector<Box> boxes;
  std::vector<Sphere> spheres;
};

/// The colours the screens draw hands in: skin, and a HIRO II's brushed metal.
inline constexpr std::array<float, 3> kSkinRgb{0.86F, 0.70F, 0.58F};
inline constexpr std::array<float, 3> kHiroRgb{0.62F, 0.64F, 0.68F};

/// Adds the hand to `parts`: the palm as a box, each link as a thin box from joint to joint,
/// each joint as a sphere; the last links stop at the fingertip spheres' surface
/// (fingertip_radius_m).
void AddHandFigure(const HandFigure& hand, double fingertip_radius_m, HandParts& parts);

/// A device with fewer fingers than a hand (msg::DeviceState::absent_fingers), drawn as what the
/// user holds: one point is a stylus (a pen rising from the fingertip, up and towards the user),
/// two to four a gripper (a handle above the points' centre with a link to each point). Only the
/// fingers in `present` (bit f is finger f) are read.
void AddDeviceFigure(const std::array<Eigen::Vector3d, kFingers>& p_WE, unsigned present, double fingertip_radius_m,
                     HandParts& parts);

/// What a device state says of a user's hand (its fields, plain).
struct DeviceHand {
  std::array<double, 3> p_WH_m{};
  std::array<double, 4> q_WH_wxyz{1.0, 0.0, 0.0, 0.0};
  std::array<Eigen::Vector3d, kFingers> p_WE{};
  unsigned absent_fingers = 0;  ///< bit f: the device has no finger f
  double fingertip_radius_m = 0.0;
  std::array<double, common::kHandJoints> q_hand_rad{};
  bool hiro = false;  ///< the user's device is a HIRO II (its member info says "hiro")
};

/// The screens' rule for a user's hand: a device with fewer than five fingers as a pen or a
/// gripper, in skin; a HIRO II's from its joint angles with its model (when there is one), in
/// brushed metal; any other fitted to its hand base and fingertips, in skin.
[[nodiscard]] HandParts DrawnHand(const DeviceHand& hand, const hiro::HiroModel* hiro_model);

}  // namespace handshare::figure
