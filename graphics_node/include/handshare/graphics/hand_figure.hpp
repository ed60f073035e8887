#pragma once
/// A user's hand on a screen: the hand figure (figure/hand_figure.hpp: the palm, the fingers'
/// links, a HIRO II's hand, a pen or gripper, as plain boxes and spheres) put into a frame's
/// scene, and a user's own view from behind their hand.
#include <Eigen/Geometry>

#include "handshare/figure/hand_figure.hpp"
#include "handshare/render/scene_view.hpp"

namespace handshare::graphics {

/// Fingers thumb first, as the device state's fingertips.
using common::kFingers;

/// Adds a drawn hand's parts to a scene's hand parts (hand_boxes, hand_spheres: drawn over the
/// scene writing no depth, so that the fingertip markers show through them), in its colour.
void AddHandParts(const figure::HandParts& parts, render::SceneView& view);

/// A user's own view: the eye at `eye_H` in the hand base's frame (default 0.30 m behind the hand
/// and 0.25 m above it: fingers along +y, the palm facing -z), looking at `look_at_H` (just ahead
/// of the fingertips, below the palm), with the world's up (+z) as up.
struct UserEye {
  Eigen::Vector3d eye_H{0.0, -0.30, 0.25};
  Eigen::Vector3d look_at_H{0.0, 0.08, -0.03};
};
[[nodiscard]] render::Camera UserEyeCamera(const Eigen::Isometry3d& X_WH, const UserEye& eye, render::Camera camera);

}  // namespace handshare::graphics
