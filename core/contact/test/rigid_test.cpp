// Rigid contact: force = k * depth on a flat face, damping along the normal, Coulomb friction
// (stick inside the static cone, slide on the kinetic cone's boundary), clamps, bad input.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include "handshare/contact/haptic_world.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

constexpr double kR = 0.008;
constexpr double kTop = 0.01;  // box 0.2 x 0.2 x 0.02 centred at the origin

std::unique_ptr<HapticWorld> MakeBlockWorld(const RigidMaterial& mat, double max_force_N = 1e3) {
  WorldConfig cfg;
  cfg.max_force_N = max_force_N;
  auto w = std::make_unique<HapticWorld>(cfg);
  w->AddStatic(Shape::Box({0.2, 0.2, 2 * kTop}), mat, Eigen::Isometry3d::Identity());
  w->Init();
  return w;
}

// Moves finger 0 in a straight line in `steps` steps of dt.
void MoveTo(HapticWorld& w, Eigen::Vector3d& p, const Eigen::Vector3d& target, int steps, double dt = 1e-3) {
  const Eigen::Vector3d p0 = p;
  for (int k = 1; k <= steps; ++k) {
    p = p0 + (target - p0) * (static_cast<double>(k) / steps);
    w.Step(dt, test::OneFinger(p));
  }
}

TEST(Rigid, ForceIsStiffnessTimesDepthOnAFlatFace) {
  const RigidMaterial mat{1500.0, 3.0, 0.0, 0.0};
  auto wp = MakeBlockWorld(mat);
  HapticWorld& w = *wp;
  Eigen::Vector3d p(0.003, -0.004, kTop + kR + 0.005);
  MoveTo(w, p, {0.003, -0.004, kTop + kR + 0.001}, 50);
  for (double depth : {0.0005, 0.001, 0.002, 0.004}) {
    MoveTo(w, p, {0.003, -0.004, kTop + kR - depth}, 100);
    w.Step(1e-3, test::OneFinger(p));  // one step at rest: no damping term
    const FingerResult& r = w.fingers()[0];
    ASSERT_TRUE(r.in_contact);
    // Exact up to round-off (the proxy's 1 um skin is taken out of the spring).
    EXPECT_NEAR(r.f_E_W_N.z(), mat.stiffness_N_per_m * depth, 1e-9);
    EXPECT_NEAR(r.f_E_W_N.head<2>().norm(), 0.0, 1e-12);
    EXPECT_NEAR(r.depth_m, depth, 1e-12);
    EXPECT_NEAR(r.n_W.z(), 1.0, 1e-12);
    EXPECT_NEAR(r.p_WC_m.z(), kTop, 1e-12);
    EXPECT_NEAR(r.e_PE_W_m.z(), -(depth + 1e-6), 1e-12);  // proxy -> fingertip, into the block
  }
}

TEST(Rigid, DampingActsAlongTheNormalOnlyAndNeverPulls) {
  const RigidMaterial mat{1000.0, 5.0, 0.0, 0.0};
  auto wp = MakeBlockWorld(mat);
  HapticWorld& w = *wp;
  Eigen::Vector3d p(0, 0, kTop + kR + 0.001);
  MoveTo(w, p, {0, 0, kTop + kR - 0.002}, 30);
  // Pressing in at v = 0.1 m/s: f = k d + b v (d measured after the step).
  const double dt = 1e-3, v = 0.1;
  p.z() -= v * dt;
  w.Step(dt, test::OneFinger(p));
  const double depth = kTop + kR - p.z();
  EXPECT_NEAR(w.fingers()[0].f_E_W_N.z(), 1000.0 * depth + 5.0 * v, 1e-9);
  // Pulling out fast: the damping would pull, the force is clipped at zero, never negative.
  p.z() += 0.0019;
  w.Step(dt, test::OneFinger(p));
  EXPECT_GE(w.fingers()[0].f_E_W_N.z(), 0.0);
  EXPECT_NEAR(w.fingers()[0].f_E_W_N.z(), 0.0, 1e-12);  // 1000 * 1e-4 - 5 * 1.9 < 0
}

TEST(Rigid, FrictionSticksInsideTheStaticConeAndSlidesOnTheKineticOne) {
  const RigidMaterial mat{1000.0, 0.0, 0.6, 0.4};
  auto wp = MakeBlockWorld(mat);
  HapticWorld& w = *wp;
  const double depth = 0.002;  // f_n = 2 N
  Eigen::Vector3d p(0, 0, kTop + kR + 0.001);
  MoveTo(w, p, {0, 0, kTop + kR - depth}, 30);
  const Eigen::Vector3d proxy0 = w.fingers()[0].p_WP_m;
  // Tangential drag of 1 mm: f_t = 1 N < 0.6 * 2 N: sticks, proxy does not move.
  MoveTo(w, p, {0.001, 0, kTop + kR - depth}, 20);
  {
    const FingerResult& r = w.fingers()[0];
    EXPECT_TRUE(r.sticking);
    EXPECT_NEAR((r.p_WP_m - proxy0).norm(), 0.0, 1e-12);
    EXPECT_NEAR(r.f_E_W_N.x(), -1.0, 1e-9);  // spring back toward the stuck proxy
    EXPECT_NEAR(r.f_E_W_N.z(), 2.0, 1e-9);
  }
  // Keep dragging: past 1.2 mm the static cone breaks, then the proxy slides with
  // |f_t| = 0.4 f_n; at no time |f_t| > mu_s f_n.
  int slipping_steps = 0;
  for (int k = 1; k <= 200; ++k) {
    p.x() += 0.0001;  // 0.1 m/s
    w.Step(1e-3, test::OneFinger(p));
    const FingerResult& r = w.fingers()[0];
    ASSERT_TRUE(r.in_contact);
    const double fn = r.f_E_W_N.z();
    const double ft = r.f_E_W_N.head<2>().norm();
    EXPECT_NEAR(fn, 2.0, 1e-9);
    EXPECT_LE(ft, 0.6 * fn + 1e-9);
    if (!r.sticking) {
      ++slipping_steps;
      // On the kinetic cone's boundary. 1e-9 N: round-off; the proxy's linearized edge
      // constraints could stop it at most its 1 nm touch band short (1e-6 N at 1000 N/m), which
      // does not happen on this face.
      EXPECT_NEAR(ft, 0.4 * fn, 1e-9) << "step " << k;
      EXPECT_LT(r.f_E_W_N.x(), 0.0);                      // opposes the motion
    }
  }
  EXPECT_GT(slipping_steps, 150);
  // Stop: the fingertip at rest with f_t = 0.8 N < mu_s f_n = 1.2 N sticks again.
  w.Step(1e-3, test::OneFinger(p));
  EXPECT_TRUE(w.fingers()[0].sticking);
}

TEST(Rigid, ForceIsClampedToTheFingerLimit) {
  auto wp = MakeBlockWorld({1000.0, 0.0, 0.0, 0.0}, 3.5);
  HapticWorld& w = *wp;
  Eigen::Vector3d p(0, 0, kTop + kR + 0.001);
  MoveTo(w, p, {0, 0, kTop + kR - 0.01}, 40);  // 10 N unclamped
  const FingerResult& r = w.fingers()[0];
  EXPECT_TRUE(r.clamped);
  EXPECT_NEAR(r.f_E_W_N.norm(), 3.5, 1e-12);
  EXPECT_NEAR(r.f_E_W_N.z(), 3.5, 1e-12);
}

TEST(Rigid, NanOrInfFingertipGivesZeroForceFlaggedAndKeepsTheProxy) {
  auto wp = MakeBlockWorld({1000.0, 2.0, 0.5, 0.4});
  HapticWorld& w = *wp;
  Eigen::Vector3d p(0, 0, kTop + kR + 0.001);
  for (int k = 0; k <= 30; ++k) {  // all five fingers press the same spot
    p.z() = kTop + kR + 0.001 - 0.003 * k / 30.0;
    w.Step(1e-3, test::OneFinger(p, false));
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  for (const Eigen::Vector3d& bad : {Eigen::Vector3d(nan, 0, 0), Eigen::Vector3d(0, inf, 0), Eigen::Vector3d(0, 0, -inf)}) {
    auto tips = test::OneFinger(p, false);  // all five fingers pressing
    tips[0] = bad;
    const StepReport rep = w.Step(1e-3, tips);
    EXPECT_EQ(rep.invalid_fingers, 1);
    for (int i = 0; i < kFingers; ++i) {
      const FingerResult& r = w.fingers()[static_cast<std::size_t>(i)];
      EXPECT_TRUE(r.f_E_W_N.allFinite());
      EXPECT_TRUE(r.p_WP_m.allFinite());
      EXPECT_TRUE(r.e_PE_W_m.allFinite());
      if (i == 0) {
        EXPECT_FALSE(r.valid);
        EXPECT_TRUE(r.f_E_W_N.isZero(0.0));
        EXPECT_FALSE(r.in_contact);
      } else {
        EXPECT_TRUE(r.valid);
        EXPECT_GT(r.f_E_W_N.z(), 0.0);
      }
    }
  }
  // Bad dt: everything zero, not ok.
  const StepReport rep = w.Step(nan, test::OneFinger(p));
  EXPECT_FALSE(rep.ok);
  for (const FingerResult& r : w.fingers()) EXPECT_TRUE(r.f_E_W_N.isZero(0.0));
  // The finger comes back deeper (it "moved" while invalid): the kept proxy is still on top.
  p.z() = -0.02;  // under the block's top, 1 cm inside
  w.Step(1e-3, test::OneFinger(p));
  EXPECT_GE(w.fingers()[0].p_WP_m.z(), kTop + kR - 1e-9);
  EXPECT_GT(w.fingers()[0].f_E_W_N.z(), 0.0);
}

}  // namespace
}  // namespace handshare::contact
