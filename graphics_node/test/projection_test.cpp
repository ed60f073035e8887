#include "handshare/render/projection.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "test_oracle.hpp"

namespace handshare::render {
namespace {

Camera SomeCamera() {
  Camera camera;
  camera.eye_W = {1.2, -0.7, 0.9};
  camera.target_W = {0.1, 0.2, 0.0};
  camera.up_W = {0.1, 0.0, 1.0};  // not orthogonal to the view direction on purpose
  camera.fov_y_rad = 0.9;
  camera.width_px = 800;
  camera.height_px = 450;
  camera.stereo_eye_separation_m = 0.07;
  return camera;
}

TEST(RenderProjection, MatchesTheIndependentPinholeOracle) {
  const Camera camera = SomeCamera();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> coordinate(-0.5, 0.5);
  for (int i = 0; i < 100; ++i) {
    const Eigen::Vector3d p_W(coordinate(rng), coordinate(rng), coordinate(rng));
    for (const auto& [eye, offset] : {std::pair{Eye::kCenter, 0.0}, std::pair{Eye::kLeft, -0.035},
                                      std::pair{Eye::kRight, 0.035}}) {
      const Eigen::Vector3d got = ProjectToImage(camera, p_W, eye);
      const test::PixelPoint want = test::OracleProject(camera, p_W, offset);
      // Both are double precision evaluations of the same closed form.
      EXPECT_NEAR(got.x(), want.col, 1e-9);
      EXPECT_NEAR(got.y(), want.row, 1e-9);
      EXPECT_NEAR(got.z(), want.depth, 1e-12);
    }
  }
}

TEST(RenderProjection, MonoProjectionIsGluPerspective) {
  const Camera camera = SomeCamera();
  const double aspect = 1.5;
  const Eigen::Matrix4d p = ProjectionMatrix(camera, aspect);
  // gluPerspective, written out from its man page.
  const double f = 1.0 / std::tan(camera.fov_y_rad / 2.0);
  const double n = camera.near_m;
  const double z = camera.far_m;
  Eigen::Matrix4d want = Eigen::Matrix4d::Zero();
  want(0, 0) = f / aspect;
  want(1, 1) = f;
  want(2, 2) = (z + n) / (n - z);
  want(2, 3) = 2.0 * z * n / (n - z);
  want(3, 2) = -1.0;
  EXPECT_TRUE(p.isApprox(want, 1e-12)) << p << "\nvs\n" << want;
}

TEST(RenderProjection, ViewMatrixMapsEyeToOriginAndTargetToMinusZ) {
  const Camera camera = SomeCamera();
  const Eigen::Matrix4d view = ViewMatrix(camera);
  EXPECT_TRUE((view * camera.eye_W.homogeneous()).isApprox(Eigen::Vector4d(0, 0, 0, 1), 1e-12));
  const Eigen::Vector4d target_Eye = view * camera.target_W.homogeneous();
  const double distance = (camera.target_W - camera.eye_W).norm();
  EXPECT_NEAR(target_Eye.x(), 0.0, 1e-12);
  EXPECT_NEAR(target_Eye.y(), 0.0, 1e-12);
  EXPECT_NEAR(target_Eye.z(), -distance, 1e-12);
  // The rotation part is orthonormal with determinant +1.
  const Eigen::Matrix3d R = view.topLeftCorner<3, 3>();
  EXPECT_TRUE((R * R.transpose()).isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
}

TEST(RenderProjection, FocalPlaneHasZeroParallax) {
  const Camera camera = SomeCamera();
  // The target and any point in its plane parallel to the image land on the same pixel.
  const Eigen::Vector3d f = (camera.target_W - camera.eye_W).normalized();
  const Eigen::Vector3d side = f.cross(camera.up_W).normalized();
  for (const Eigen::Vector3d& p_W : {camera.target_W, Eigen::Vector3d(camera.target_W + 0.2 * side)}) {
    const Eigen::Vector3d left = ProjectToImage(camera, p_W, Eye::kLeft);
    const Eigen::Vector3d right = ProjectToImage(camera, p_W, Eye::kRight);
    EXPECT_NEAR(left.x(), right.x(), 1e-9);
    EXPECT_NEAR(left.y(), right.y(), 1e-9);
  }
  const Eigen::Vector3d centre = ProjectToImage(camera, camera.target_W);
  EXPECT_NEAR(centre.x(), camera.width_px / 2.0, 1e-9);
  EXPECT_NEAR(centre.y(), camera.height_px / 2.0, 1e-9);
}

TEST(RenderProjection, InvalidCamerasAreRejectedWithTheField) {
  const auto expect_error = [](Camera camera, const std::string& field) {
    try {
      ValidateCamera(camera);
      ADD_FAILURE() << "expected std::invalid_argument about " << field;
    } catch (const std::invalid_argument& e) {
      EXPECT_NE(std::string(e.what()).find(field), std::string::npos) << e.what();
    }
  };
  Camera camera = SomeCamera();
  EXPECT_NO_THROW(ValidateCamera(camera));
  camera.target_W = camera.eye_W;
  expect_error(camera, "target_W");
  camera = SomeCamera();
  camera.up_W = camera.target_W - camera.eye_W;
  expect_error(camera, "up_W");
  camera = SomeCamera();
  camera.fov_y_rad = 3.2;
  expect_error(camera, "fov_y_rad");
  camera = SomeCamera();
  camera.width_px = 0;
  expect_error(camera, "size");
  camera = SomeCamera();
  camera.near_m = 0.0;
  expect_error(camera, "near_m");
  camera = SomeCamera();
  camera.eye_W.x() = std::nan("");
  expect_error(camera, "eye_W");
}

}  // namespace
}  // namespace handshare::render
