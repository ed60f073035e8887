#pragma once
/// A user's hand as the screens draw it: a palm and five fingers of three links each, fitted to
/// the device's hand base and fingertips (what every device reports), so a spectator sees a hand
/// where it used to see five dots, and a user sees their own hand in their own view.
#include <array>

#include <Eigen/Geometry>

#include "handshare/common/hand.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::hiro {
struct HiroModel;
}

namespace handshare::graphics {

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

/// Adds the hand to a scene's hand parts: the palm as a box, each link as a thin box from joint
/// to joint, each joint as a sphere. The fingertips are the caller's to draw, as markers of
/// fingertip_radius_m (seen through the hand); the last links stop at their surface.
void AddHandFigure(const HandFigure& hand, double fingertip_radius_m, const render::Rgb& skin,
                   render::SceneView& view);

/// A device with fewer fingers than a hand (msg::DeviceState::absent_fingers), drawn as what the
/// user holds: one point is a stylus (a pen rising from the fingertip, up and towards the user),
/// two to four a gripper (a handle above the points' centre with a link to each point). Only the
/// fingers in `present` (bit f is finger f) are read; the caller draws their fingertip markers.
void AddDeviceFigure(const std::array<Eigen::Vector3d, kFingers>& p_WE, unsigned present, double fingertip_radius_m,
                     const render::Rgb& rgb, render::SceneView& view);

/// A user's own view: the eye at `eye_H` in the hand base's frame (default 0.30 m behind the hand
/// and 0.25 m above it: fingers along +y, the palm facing -z), looking at `look_at_H` (just ahead
/// of the fingertips, below the palm), with the world's up (+z) as up.
struct UserEye {
  Eigen::Vector3d eye_H{0.0, -0.30, 0.25};
  Eigen::Vector3d look_at_H{0.0, 0.08, -0.03};
};
[[nodiscard]] render::Camera UserEyeCamera(const Eigen::Isometry3d& X_WH, const UserEye& eye, render::Camera camera);

}  // namespace handshare::graphics
