// A dynamic body handed over from another simulation (the world server taking over a ball its
// owner let go, a haptic node taking over a ball it followed) keeps its motion: SetVelocity.
#include <gtest/gtest.h>

#include <cmath>

#include "handshare/contact/haptic_world.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

TEST(Handover, BodyKeepsTheVelocityItWasHandedOver) {
  HapticWorld w;
  BodyProperties body;
  body.mass_kg = 0.2;
  const ObjectId ball = w.AddDynamic(Shape::Sphere(0.03, 3), RigidMaterial{}, body,
                                     Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0.5)));
  const ObjectId wall = w.AddStatic(Shape::Box(Eigen::Vector3d(0.01, 0.01, 0.01)), RigidMaterial{},
                                    Eigen::Isometry3d(Eigen::Translation3d(1, 0, 0)));
  const double g = kMarsGravity_m_per_s2;
  w.SetGravity(Eigen::Vector3d(0, 0, -g));
  w.Init();
  const auto far = test::OneFinger(Eigen::Vector3d(-1, -1, -1));
  const Eigen::Vector3d p0(0.1, -0.2, 0.4), v0(0.3, -0.1, 0.5), w0(0.0, 0.0, 2.0);
  w.SetPose(ball, Eigen::Isometry3d(Eigen::Translation3d(p0)));
  EXPECT_EQ(w.body_velocity_W(ball).norm(), 0.0);  // SetPose alone: at rest
  w.SetVelocity(ball, v0, w0);
  EXPECT_EQ((w.body_velocity_W(ball) - v0).norm(), 0.0);
  // Semi-implicit Euler, n = 100 steps of 1 ms: p0 + v0 t - g dt^2 n (n + 1) / 2 (no damping).
  for (int k = 0; k < 100; ++k) w.Step(1e-3, far);
  const Eigen::Vector3d expected = p0 + v0 * 0.1 - Eigen::Vector3d(0, 0, g * 1e-6 * 100 * 101 / 2);
  EXPECT_LT((w.pose(ball).translation() - expected).norm(), 1e-12);
  // It turned about z at 2 rad/s: 0.2 rad (a sphere's inertia is isotropic: no precession).
  const Eigen::AngleAxisd turned(w.pose(ball).linear());
  EXPECT_NEAR(turned.angle(), 0.2, 1e-9);
  EXPECT_NEAR(std::abs(turned.axis().z()), 1.0, 1e-9);

  // Not finite: ignored. A static object has no velocity to set.
  const Eigen::Vector3d v_before = w.body_velocity_W(ball);
  w.SetVelocity(ball, Eigen::Vector3d(std::nan(""), 0, 0), Eigen::Vector3d::Zero());
  EXPECT_EQ((w.body_velocity_W(ball) - v_before).norm(), 0.0);
  w.SetVelocity(wall, v0, w0);
  EXPECT_EQ(w.body_velocity_W(wall).norm(), 0.0);
  EXPECT_EQ(w.pose(wall).translation().x(), 1.0);
  w.SetVelocity(-1, v0, w0);  // out of range: ignored
  w.SetVelocity(99, v0, w0);
}

}  // namespace
}  // namespace handshare::contact
