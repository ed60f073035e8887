#pragma once
// An independent pinhole projection for the tests, written from the convention stated in
// scene_view.hpp (gluLookAt + gluPerspective + off-axis stereo) without the library's matrices.

#include <cmath>

#include <Eigen/Core>

#include "handshare/render/scene_view.hpp"

namespace handshare::render::test {

struct PixelPoint {
  double col;    // continuous column, 0 at the left edge
  double row;    // continuous row, 0 at the top edge
  double depth;  // distance along the view direction [m]
};

/// eye_offset_m: 0 for mono, -/+ separation / 2 for the left / right stereo eye.
inline PixelPoint OracleProject(const Camera& camera, const Eigen::Vector3d& p_W,
                                double eye_offset_m = 0.0) {
  const Eigen::Vector3d f = (camera.target_W - camera.eye_W).normalized();
  const Eigen::Vector3d s = f.cross(camera.up_W).normalized();
  const Eigen::Vector3d u = s.cross(f);
  const Eigen::Vector3d d = p_W - camera.eye_W;
  const double x = s.dot(d);
  const double y = u.dot(d);
  const double depth = f.dot(d);
  const double c = 1.0 / std::tan(camera.fov_y_rad / 2.0);
  const double aspect = static_cast<double>(camera.width_px) / camera.height_px;
  const double focal_m = (camera.target_W - camera.eye_W).norm();
  const double x_ndc = (c / aspect) * ((x - eye_offset_m) / depth + eye_offset_m / focal_m);
  const double y_ndc = c * y / depth;
  return {(x_ndc + 1.0) / 2.0 * camera.width_px, (1.0 - y_ndc) / 2.0 * camera.height_px, depth};
}

}  // namespace handshare::render::test
