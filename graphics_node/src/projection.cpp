#include "handshare/render/projection.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace handshare::render {

namespace {

void Require(bool ok, const std::string& what) {
  if (!ok) throw std::invalid_argument("render::Camera: " + what);
}

struct CameraBasis {
  Eigen::Vector3d s;  // right
  Eigen::Vector3d u;  // up
  Eigen::Vector3d f;  // forward
};

CameraBasis Basis(const Camera& camera) {
  CameraBasis b;
  b.f = (camera.target_W - camera.eye_W).normalized();
  b.s = b.f.cross(camera.up_W).normalized();
  b.u = b.s.cross(b.f);
  return b;
}

// Signed offset of an eye along s [m].
double EyeOffset_m(const Camera& camera, Eye eye) {
  switch (eye) {
    case Eye::kLeft: return -0.5 * camera.stereo_eye_separation_m;
    case Eye::kRight: return 0.5 * camera.stereo_eye_separation_m;
    case Eye::kCenter: break;
  }
  return 0.0;
}

}  // namespace

void ValidateCamera(const Camera& camera) {
  Require(camera.eye_W.allFinite(), "eye_W is not finite");
  Require(camera.target_W.allFinite(), "target_W is not finite");
  Require(camera.up_W.allFinite(), "up_W is not finite");
  const Eigen::Vector3d forward = camera.target_W - camera.eye_W;
  Require(forward.norm() > 1e-9, "eye_W and target_W coincide");
  Require(camera.up_W.norm() > 1e-12, "up_W is zero");
  Require(forward.normalized().cross(camera.up_W.normalized()).norm() > 1e-6,
          "up_W is parallel to the view direction");
  Require(camera.fov_y_rad > 0.0 && camera.fov_y_rad < std::numbers::pi,
          "fov_y_rad = " + std::to_string(camera.fov_y_rad) + " is not in (0, pi)");
  Require(camera.width_px > 0 && camera.height_px > 0,
          "size " + std::to_string(camera.width_px) + " x " + std::to_string(camera.height_px) +
              " px is not positive");
  Require(camera.near_m > 0.0 && camera.far_m > camera.near_m && std::isfinite(camera.far_m),
          "clip range near_m = " + std::to_string(camera.near_m) +
              ", far_m = " + std::to_string(camera.far_m) + " needs 0 < near < far");
  Require(std::isfinite(camera.stereo_eye_separation_m) && camera.stereo_eye_separation_m >= 0.0,
          "stereo_eye_separation_m must be finite and >= 0");
}

Eigen::Matrix4d ViewMatrix(const Camera& camera, Eye eye) {
  const CameraBasis b = Basis(camera);
  const Eigen::Vector3d p_WEye = camera.eye_W + EyeOffset_m(camera, eye) * b.s;
  // gluLookAt: rows s, u, -f, then translate by -eye.
  Eigen::Matrix4d view = Eigen::Matrix4d::Identity();
  view.block<1, 3>(0, 0) = b.s.transpose();
  view.block<1, 3>(1, 0) = b.u.transpose();
  view.block<1, 3>(2, 0) = -b.f.transpose();
  view(0, 3) = -b.s.dot(p_WEye);
  view(1, 3) = -b.u.dot(p_WEye);
  view(2, 3) = b.f.dot(p_WEye);
  return view;
}

Eigen::Matrix4d ProjectionMatrix(const Camera& camera, double aspect, Eye eye) {
  const double n = camera.near_m;
  const double f = camera.far_m;
  const double top = n * std::tan(0.5 * camera.fov_y_rad);
  const double half_width = top * aspect;
  // Off-axis frustum: shift the window so the focal plane has zero parallax.
  const double focal_m = (camera.target_W - camera.eye_W).norm();
  const double shift = -EyeOffset_m(camera, eye) * n / focal_m;
  const double l = -half_width + shift;
  const double r = half_width + shift;
  const double b = -top;
  const double t = top;
  // glFrustum(l, r, b, t, n, f).
  Eigen::Matrix4d proj = Eigen::Matrix4d::Zero();
  proj(0, 0) = 2.0 * n / (r - l);
  proj(0, 2) = (r + l) / (r - l);
  proj(1, 1) = 2.0 * n / (t - b);
  proj(1, 2) = (t + b) / (t - b);
  proj(2, 2) = -(f + n) / (f - n);
  proj(2, 3) = -2.0 * f * n / (f - n);
  proj(3, 2) = -1.0;
  return proj;
}

Eigen::Vector3d ProjectToImage(const Camera& camera, const Eigen::Vector3d& p_W, Eye eye) {
  const double aspect = static_cast<double>(camera.width_px) / camera.height_px;
  const Eigen::Vector4d clip =
      ProjectionMatrix(camera, aspect, eye) * ViewMatrix(camera, eye) * p_W.homogeneous();
  const double depth_m = clip.w();  // w_clip = -z_eye = depth along f.
  const double x_ndc = clip.x() / clip.w();
  const double y_ndc = clip.y() / clip.w();
  return {(x_ndc + 1.0) * 0.5 * camera.width_px, (1.0 - y_ndc) * 0.5 * camera.height_px, depth_m};
}

}  // namespace handshare::render
