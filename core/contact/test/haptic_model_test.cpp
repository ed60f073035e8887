// The haptic world as model and data: a HapticModel (what the objects are) is const once built,
// and every HapticWorld on it steps data of its own (poses, velocities, proxies, solver states).
#include <gtest/gtest.h>

#include <array>
#include <memory>
#include <stdexcept>
#include <vector>

#include "handshare/contact/haptic_world.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

// A table, a ball resting on it and the soft block with friction: every kind of object.
std::unique_ptr<HapticWorld> MakeScene() {
  static const test::SoftBlock soft = test::MakeSoftBlock();
  auto w = std::make_unique<HapticWorld>(WorldConfig{.max_hands = 2, .max_force_N = 5.0});
  w->AddStatic(Shape::Box({0.5, 0.5, 0.02}), RigidMaterial{}, Eigen::Isometry3d(Eigen::Translation3d(0, 0, -0.01)));
  BodyProperties ball;
  ball.mass_kg = 0.2;
  w->AddDynamic(Shape::Sphere(0.03), RigidMaterial{}, ball, Eigen::Isometry3d(Eigen::Translation3d(0.2, 0, 0.03)));
  DeformableDesc d;
  d.mesh = soft.mesh;
  d.compliance = soft.C;
  d.X_WO = Eigen::Translation3d(0, 0.2, 0) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  d.mu_static = 0.5;
  d.mu_kinetic = 0.4;
  w->AddDeformable(d);
  w->SetSupport(SupportPlane{});
  w->Init();
  return w;
}

// A finger pressing and stroking the block, one pushing the ball, and a peer on the block.
void Drive(HapticWorld& w, int step) {
  const double t = 1e-3 * step;
  const Eigen::Isometry3d X_WB = Eigen::Translation3d(0, 0.2, 0) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  const std::array<Eigen::Vector3d, 2> tips = {
      X_WB * Eigen::Vector3d(0.03 + 0.01 * t, 0.03, 0.038 - 0.004 * std::min(1.0, 4 * t)),
      Eigen::Vector3d(0.2 - 0.037 + 0.01 * t, 0.0, 0.03)};
  FingerContact peer;
  peer.object = 2;
  peer.p_OC_m = {0.02, 0.02, 0.03};
  peer.n_O = {0, 0, 1};
  peer.u_O_m = {0.0002, 0, -0.002};
  const StepReport r = w.Step(1e-3, tips, std::span<const FingerContact>(&peer, 1));
  ASSERT_TRUE(r.ok);
}

void ExpectSame(const HapticWorld& a, const HapticWorld& b) {
  for (int i = 0; i < kFingers; ++i) {
    const FingerResult& x = a.fingers()[static_cast<std::size_t>(i)];
    const FingerResult& y = b.fingers()[static_cast<std::size_t>(i)];
    EXPECT_EQ(x.f_E_W_N, y.f_E_W_N) << i;
    EXPECT_EQ(x.p_WP_m, y.p_WP_m) << i;
    EXPECT_EQ(x.u_W_m, y.u_W_m) << i;
    EXPECT_EQ(x.object, y.object) << i;
    EXPECT_EQ(x.sticking, y.sticking) << i;
  }
  for (ObjectId k = 0; k < a.num_objects(); ++k) {
    EXPECT_EQ(a.pose(k).matrix(), b.pose(k).matrix()) << k;
    EXPECT_EQ(a.body_velocity_W(k), b.body_velocity_W(k)) << k;
  }
  ASSERT_EQ(a.remote_forces_O().size(), b.remote_forces_O().size());
  for (std::size_t r = 0; r < a.remote_forces_O().size(); ++r) EXPECT_EQ(a.remote_forces_O()[r], b.remote_forces_O()[r]);
}

// One model, two worlds: the second starts where the model puts the objects and steps exactly
// as a world built on a model of its own, and neither world's steps move the other.
TEST(HapticModel, WorldsOnOneModelStepDataOfTheirOwn) {
  const auto built = MakeScene();
  const auto separate = MakeScene();
  const std::shared_ptr<const HapticModel> model = built->shared_model();
  ASSERT_NE(model, nullptr);
  EXPECT_EQ(&built->model(), model.get());
  EXPECT_EQ(model->num_objects(), 3);
  EXPECT_TRUE(model->has_support());
  HapticWorld shared(model);
  EXPECT_EQ(&shared.model(), model.get());
  // Only the world on the shared model steps: the one that built the model stays as built.
  for (int s = 0; s < 300; ++s) {
    Drive(shared, s);
    Drive(*separate, s);
    ExpectSame(shared, *separate);
  }
  EXPECT_GT(shared.fingers()[0].f_E_W_N.norm(), 0.1);   // pressed the block
  EXPECT_GT(shared.fingers()[1].f_E_W_N.norm(), 0.01);  // pushed the ball
  EXPECT_NE(shared.pose(1).translation(), built->pose(1).translation());
  const auto fresh = MakeScene();
  for (ObjectId k = 0; k < built->num_objects(); ++k) EXPECT_EQ(built->pose(k).matrix(), fresh->pose(k).matrix());
  Eigen::Vector3d p;
  EXPECT_FALSE(built->proxy_W(0, 2, p));  // its proxies never started
  // Now the builder steps too: from the start, as the others did.
  for (int s = 0; s < 300; ++s) Drive(*built, s);
  ExpectSame(*built, shared);
}

TEST(HapticModel, IsFrozenByInitAndNeverNull) {
  HapticWorld w;
  EXPECT_EQ(w.shared_model(), nullptr);  // still being built
  w.AddStatic(Shape::Sphere(0.05), RigidMaterial{}, Eigen::Isometry3d::Identity());
  w.Init();
  ASSERT_NE(w.shared_model(), nullptr);
  EXPECT_THROW(w.AddStatic(Shape::Sphere(0.05), RigidMaterial{}, Eigen::Isometry3d::Identity()), std::logic_error);
  HapticWorld other(w.shared_model());
  EXPECT_THROW(other.SetSupport(SupportPlane{}), std::logic_error);  // the model is shared and const
  EXPECT_THROW(other.Init(), std::logic_error);
  EXPECT_THROW(HapticWorld(std::shared_ptr<const HapticModel>()), std::invalid_argument);
}

}  // namespace
}  // namespace handshare::contact
