// HapticWorld::Step must not allocate: handshare::allocation_counter counts operator new.
#include <gtest/gtest.h>

#include <cmath>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/testing/allocation_counter.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

TEST(RealTime, StepDoesNotAllocate) {
  // Every kind of object: a static bumpy mesh, a thin plate, a dynamic ball on a support, and a
  // deformable block with friction and a remote hand on it.
  HapticWorld w;
  w.AddStatic(Shape::Mesh(std::make_shared<TriMesh>(MakeBumpySphere(0.05, 0.003, 3))), RigidMaterial{},
              Eigen::Isometry3d(Eigen::Translation3d(0, 0, 0)));
  w.AddStatic(Shape::Box({0.1, 0.1, 0.001}), RigidMaterial{}, Eigen::Isometry3d(Eigen::Translation3d(0.2, 0, 0)));
  const ObjectId ball = w.AddDynamic(Shape::Sphere(0.03, 3), RigidMaterial{}, BodyProperties{},
                                     Eigen::Isometry3d(Eigen::Translation3d(0.4, 0, 0.03)));
  auto mesh = std::make_shared<fem::TetMesh>(fem::MakeBoxMesh({0.04, 0.04, 0.02}, {8, 8, 4}));
  auto C = std::make_shared<const fem::Compliance>(
      fem::Compliance::Precompute(*mesh, fem::Material{2e4, 0.3}, fem::NodesOnPlane(*mesh, 2, 0.0)));
  DeformableDesc d;
  d.mesh = mesh;
  d.compliance = C;
  d.X_WO = Eigen::Translation3d(0.6, 0, 0) * Eigen::Isometry3d::Identity();
  d.mu_static = 0.6;  // friction on: its patches, anchors and slips must not allocate either
  d.mu_kinetic = 0.5;
  const ObjectId block = w.AddDeformable(d);
  w.SetSupport(SupportPlane{});
  w.Init();
  std::array<FingerContact, 1> remote = {
      ContactInObjectFrame(d.X_WO, 0, block, Eigen::Vector3d(0.63, 0.03, 0.02), Eigen::Vector3d(0.63, 0.03, 0.027),
                           Eigen::Vector3d(0, 0, -0.001), Eigen::Vector3d(0, 0, 0.1))};
  // Fingers sweep across every object, in and out of contact, with a NaN now and then.
  auto tips_at = [&](int k) {
    std::array<Eigen::Vector3d, kFingers> tips;
    const double t = k * 1e-3;
    for (int i = 0; i < kFingers; ++i) {
      const double x = -0.05 + 0.7 * std::fmod(0.25 * t + 0.01 * i, 1.0);
      tips[static_cast<std::size_t>(i)] = Eigen::Vector3d(x, 0.01 * i - 0.02, 0.03 + 0.025 * std::sin(20 * t + i));
    }
    if (k % 97 == 0) tips[2].x() = std::nan("");
    return tips;
  };
  for (int k = 0; k < 10; ++k) w.Step(1e-3, tips_at(k), remote);  // warm-up
  int contacts = 0;
  const long before = testing::AllocationCount();
  for (int k = 10; k < 4000; ++k) {
    w.Step(1e-3, tips_at(k), remote);
    for (const FingerResult& r : w.fingers()) contacts += r.in_contact ? 1 : 0;
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_GT(contacts, 1000);  // the trajectory did touch things
  (void)ball;
}

}  // namespace
}  // namespace handshare::contact
