#include "handshare/graphics/hand_figure.hpp"

#include <cmath>

namespace handshare::graphics {

void AddHandParts(const figure::HandParts& parts, render::SceneView& view) {
  const render::Rgb rgb{parts.rgb[0], parts.rgb[1], parts.rgb[2]};
  for (const figure::Box& b : parts.boxes) {
    render::Box box;
    box.p_W = b.p_W;
    box.half_extents_m = b.half_extents_m;
    box.q_WB = b.q_WB;
    box.rgb = rgb;
    view.hand_boxes.push_back(box);
  }
  for (const figure::Sphere& s : parts.spheres) view.hand_spheres.push_back(render::Sphere{s.p_W, s.radius_m, rgb});
}

render::Camera UserEyeCamera(const Eigen::Isometry3d& X_WH, const UserEye& eye, render::Camera camera) {
  // Only the hand base's heading turns the view (yaw about +z): a tilted or rolled hand does
  // not tilt the user's head.
  Eigen::Vector3d forward = X_WH.linear() * Eigen::Vector3d::UnitY();
  forward.z() = 0.0;
  const double yaw = forward.norm() > 1e-9 ? std::atan2(-forward.x(), forward.y()) : 0.0;
  const Eigen::Isometry3d X_WY = Eigen::Translation3d(X_WH.translation()) * Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ());
  camera.eye_W = X_WY * eye.eye_H;
  camera.target_W = X_WY * eye.look_at_H;
  camera.up_W = Eigen::Vector3d::UnitZ();
  return camera;
}

}  // namespace handshare::graphics
