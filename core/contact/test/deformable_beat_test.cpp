// A beating deformable (DeformableDesc::mode_O_m, SetModeScale): its surface is at rest + s M,
// and a fingertip presses that moved surface. The force is the contact's part of the field
// (linear elasticity: it adds to s M), so a press of depth d below the moved surface feels
// exactly what the same press below the resting surface feels.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/testing/allocation_counter.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

constexpr double kR = 0.008;
constexpr double kTop = 0.03;  // the soft block's top face, frame O

struct Beating {
  std::unique_ptr<HapticWorld> world;
  ObjectId id = -1;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
};

// The soft block at a rotated, shifted pose, with a mode that lifts the top face by lift(x)
// (linear in z from the fixed bottom: M = lift(x) z / top along O's z).
Beating MakeBeating(double lift_at_0, double lift_slope_per_m) {
  static const test::SoftBlock soft = test::MakeSoftBlock();
  Beating b;
  b.world = std::make_unique<HapticWorld>(WorldConfig{.max_hands = 2, .max_force_N = 100.0});
  DeformableDesc d;
  d.mesh = soft.mesh;
  d.compliance = soft.C;
  b.X_WO = Eigen::Translation3d(0.1, -0.05, 0.2) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  d.X_WO = b.X_WO;
  d.max_patch_nodes = 32;
  auto mode = std::make_shared<std::vector<Eigen::Vector3d>>();
  for (const auto& p : soft.mesh->positions_m()) {
    mode->emplace_back(0.0, 0.0, (lift_at_0 + lift_slope_per_m * p.x()) * p.z() / kTop);
  }
  d.mode_O_m = mode;
  b.id = b.world->AddDeformable(d);
  b.world->Init();
  return b;
}

// Lowers finger 0 at (x, y) of O from 2 mm above height `surface_z` (O) to `depth` below it.
const FingerResult& Press(HapticWorld& w, const Eigen::Isometry3d& X_WO, double x, double y, double surface_z,
                          double depth) {
  for (int k = 0; k <= 40; ++k) {
    std::array<Eigen::Vector3d, kFingers> tips;
    for (int i = 0; i < kFingers; ++i) tips[static_cast<std::size_t>(i)] = Eigen::Vector3d(5.0, 5.0, 5.0 + i);
    const double h = 0.002 - (0.002 + depth) * k / 40.0;
    tips[0] = X_WO * Eigen::Vector3d(x, y, surface_z + kR + h);
    w.Step(1e-3, tips);
  }
  return w.fingers()[0];
}

TEST(DeformableBeat, APressBelowTheMovedSurfaceFeelsThePressBelowTheRestingOne) {
  // The resting block pressed 2 mm: the reference.
  Beating rest = MakeBeating(0.004, 0.0);
  const FingerResult r0 = Press(*rest.world, rest.X_WO, 0.03, 0.03, kTop, 0.002);
  ASSERT_TRUE(r0.in_contact);
  ASSERT_GT(r0.f_E_W_N.norm(), 0.05);
  // Beating, at s = 0.5 and s = -0.75: the top has moved by s 4 mm; 2 mm below it.
  for (const double s : {0.5, -0.75}) {
    Beating b = MakeBeating(0.004, 0.0);
    b.world->SetModeScale(b.id, s);
    EXPECT_EQ(b.world->mode_scale(b.id), s);
    const FingerResult r = Press(*b.world, b.X_WO, 0.03, 0.03, kTop + s * 0.004, 0.002);
    ASSERT_TRUE(r.in_contact) << s;
    EXPECT_NEAR(r.depth_m, 0.002, 1e-9) << s;
    EXPECT_LT((r.f_E_W_N - r0.f_E_W_N).norm(), 1e-9 * r0.f_E_W_N.norm()) << s;
    EXPECT_EQ(r.patch_nodes, r0.patch_nodes) << s;
    // The proxy sits on the moved surface (skin off it), the contact point on the resting one
    // (where the peers' and the server's patches are found).
    const Eigen::Vector3d proxy_O = b.X_WO.inverse() * r.p_WP_m;
    EXPECT_NEAR(proxy_O.z(), kTop + s * 0.004 + kR, 1e-5) << s;
    EXPECT_NEAR((b.X_WO.inverse() * r.p_WC_m).z(), kTop, 1e-9) << s;
    // The same fingertip where the resting surface was: pressed deeper or free, as the
    // surface moved.
    Beating c = MakeBeating(0.004, 0.0);
    c.world->SetModeScale(c.id, s);
    const FingerResult at_rest = Press(*c.world, c.X_WO, 0.03, 0.03, kTop, 0.001);
    if (s > 0.0) {
      ASSERT_TRUE(at_rest.in_contact);
      EXPECT_NEAR(at_rest.depth_m, 0.001 + s * 0.004, 1e-9);
    } else {
      EXPECT_FALSE(at_rest.in_contact);
      EXPECT_EQ(at_rest.f_E_W_N.norm(), 0.0);
    }
  }
}

TEST(DeformableBeat, TheModeIsReadWhereTheFingertipIs) {
  // A top face lifted by (2 + 50 x) mm at s = 1 (x in m: 2 mm at x = 0, 5 mm at x = 6 cm):
  // at x = 1 cm and x = 5 cm the press is 2 mm below the surface moved there.
  for (const double x : {0.01, 0.05}) {
    Beating b = MakeBeating(0.002, 0.05);
    b.world->SetModeScale(b.id, 1.0);
    const double lift = 0.002 + 0.05 * x;
    const FingerResult r = Press(*b.world, b.X_WO, x, 0.03, kTop + lift, 0.002);
    ASSERT_TRUE(r.in_contact) << x;
    EXPECT_NEAR(r.depth_m, 0.002, 1e-9) << x;
  }
}

TEST(DeformableBeat, ABeatingStepDoesNotAllocate) {
  Beating b = MakeBeating(0.004, 0.0);
  b.world->SetModeScale(b.id, 0.3);
  Press(*b.world, b.X_WO, 0.03, 0.03, kTop + 0.3 * 0.004, 0.002);  // warm: in contact
  const long before = testing::AllocationCount();
  std::array<Eigen::Vector3d, kFingers> tips;
  for (int i = 0; i < kFingers; ++i) tips[static_cast<std::size_t>(i)] = b.X_WO * Eigen::Vector3d(0.03, 0.03, kTop + kR - 0.003);
  for (int k = 0; k < 200; ++k) {
    b.world->SetModeScale(b.id, 0.5 * std::sin(0.05 * k));  // the tips stay 1-5 mm deep
    b.world->Step(1e-3, tips);
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  EXPECT_TRUE(b.world->fingers()[0].in_contact);
}

TEST(DeformableBeat, BadModesAreRefusedAtSetup) {
  static const test::SoftBlock soft = test::MakeSoftBlock();
  HapticWorld w;
  DeformableDesc d;
  d.mesh = soft.mesh;
  d.compliance = soft.C;
  d.mode_O_m = std::make_shared<std::vector<Eigen::Vector3d>>(3, Eigen::Vector3d::Zero());
  EXPECT_THROW(w.AddDeformable(d), std::invalid_argument);
  std::vector<Eigen::Vector3d> nan(soft.mesh->positions_m().size(), Eigen::Vector3d::Zero());
  nan[5].x() = std::numeric_limits<double>::quiet_NaN();
  d.mode_O_m = std::make_shared<const std::vector<Eigen::Vector3d>>(std::move(nan));
  EXPECT_THROW(w.AddDeformable(d), std::invalid_argument);
  // Without a mode the scale stays 0 (nothing to move); a non-finite scale is ignored.
  d.mode_O_m.reset();
  const ObjectId id = w.AddDeformable(d);
  w.SetModeScale(id, 0.5);
  EXPECT_EQ(w.mode_scale(id), 0.0);
}

}  // namespace
}  // namespace handshare::contact
