#include "desk_device.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "handshare/common/clock.hpp"
#include "handshare/haptic/force_renderer.hpp"
#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/haptic/sim_hand.hpp"
#include "handshare/testing/allocation_counter.hpp"

namespace handshare::haptic {
namespace {

constexpr double kDt_s = 1e-3;  // the haptic loop's period

DeskTarget Target(const Eigen::Vector3d& p_WH, double closure, double yaw_rad = 0.0, bool focused = true) {
  DeskTarget t;
  t.p_WH_m = {p_WH.x(), p_WH.y(), p_WH.z()};
  const Eigen::Quaterniond q(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()));
  t.q_WH_wxyz = {q.w(), q.x(), q.y(), q.z()};
  t.closure.fill(closure);
  t.focused = focused;
  t.received_ns = common::SteadyNowNs();
  return t;
}

// A table top at z = 0 under every fingertip: k times the depth of the fingertip sphere, up
// (rigid contact's default stiffness, contact::RigidMaterial, 1000 N/m).
class Floor final : public ForceRenderer {
 public:
  void Render(double, double, std::uint64_t, const DeviceReading& r,
              std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept override {
    for (int i = 0; i < kFingers; ++i) {
      const double depth = kSimFingertipRadius_m - r.p_WE[i].z();
      f_E_W[i] = Eigen::Vector3d(0, 0, depth > 0.0 ? 1000.0 * depth : 0.0);
      max_depth_m = std::max(max_depth_m, depth);
    }
  }
  double max_depth_m = -1.0;
};

// The same hand without the filter: fingertips at the target as it arrives (what a desk
// without smoothing would give the loop).
class UnfilteredDesk final : public Device {
 public:
  DeviceCapabilities capabilities() const noexcept override { return {}; }
  void Read(double, DeviceReading& out) noexcept override {
    out.p_WH = Eigen::Vector3d(target.p_WH_m.data());
    for (int i = 0; i < kFingers; ++i) out.p_WE[i] = out.p_WH + DeskFingertip_H(i, target.closure[i]);
    out.stamp_ns = common::SteadyNowNs();
    out.valid = true;
  }
  void Command(const std::array<Eigen::Vector3d, kFingers>&) noexcept override {}
  const char* name() const noexcept override { return "unfiltered"; }
  DeskTarget target;
};

// A person's session at the desk in steps, as the view sends them: down onto the table top in
// one jump, across it, the hand closed at once, turned, and up again; each target held 1 s.
template <class Post>
void DeskSession(HapticLoop& loop, Post post) {
  const Eigen::Vector3d above(0.0, -0.1, 0.10), on(0.0, -0.1, 0.012), across(0.3, 0.1, 0.012);
  const DeskTarget steps[] = {Target(above, 0.0),         Target(on, 0.0),           Target(across, 0.0),
                              Target(across, 1.0),        Target(across, 1.0, 1.2),  Target(above, 0.0, 1.2),
                              Target(on, 0.5, -0.8)};
  double t_s = 0.0;
  for (const DeskTarget& s : steps) {
    for (int i = 0; i < 1000; ++i, t_s += kDt_s) {
      DeskTarget fresh = s;
      fresh.received_ns = common::SteadyNowNs();
      post(fresh);
      loop.Step(t_s);
    }
  }
}

TEST(DeskDevice, NoTargetYetIsNotAValidHand) {
  DeskDevice desk;
  DeviceReading r;
  r.valid = true;
  desk.Read(0.0, r);
  EXPECT_FALSE(r.valid);
}

TEST(DeskDevice, StepsOfTheTargetNeverTripTheForceRateBound) {
  // The oracle first: the same steps unfiltered trip the safety's rate bound.
  {
    UnfilteredDesk raw;
    HapticLoop loop(raw, HapticLoopConfig{1000.0, false});
    auto floor = std::make_shared<Floor>();
    loop.SetRenderer(floor);
    DeskSession(loop, [&](const DeskTarget& t) { raw.target = t; });
    ASSERT_GT(floor->max_depth_m, 0.01) << "the session must press into the table";
    ASSERT_GT(loop.rate_limited_steps(), 0u) << "the oracle: unfiltered steps must trip the rate bound";
  }
  DeskDevice desk;
  HapticLoop loop(desk, HapticLoopConfig{1000.0, false});
  auto floor = std::make_shared<Floor>();
  loop.SetRenderer(floor);
  DeskSession(loop, [&](const DeskTarget& t) { desk.Post(t); });
  EXPECT_GT(floor->max_depth_m, 0.01) << "the filtered hand must reach the table top too";
  EXPECT_EQ(loop.rate_limited_steps(), 0u);
  EXPECT_EQ(loop.faults(), 0u);
}

TEST(DeskDevice, AStepGivesBoundedFingertipSpeedAndAccelerationAndArrives) {
  DeskDevice desk;
  desk.Post(Target(Eigen::Vector3d(-0.3, -0.3, 0.25), 0.0, -1.5));
  DeviceReading r;
  desk.Read(0.0, r);
  ASSERT_TRUE(r.valid);
  // Everything at once: across the whole workspace, turned by 3 rad, every finger closed.
  const DeskTarget far = Target(Eigen::Vector3d(0.3, 0.3, 0.0), 1.0, 1.5);
  desk.Post(far);
  auto prev = r.p_WE;
  std::array<Eigen::Vector3d, kFingers> v_prev{};
  for (auto& v : v_prev) v.setZero();
  double max_speed = 0.0, max_acceleration = 0.0;
  for (int k = 1; k <= 6000; ++k) {
    if (k % 100 == 0) {  // the view keeps sending the same target
      DeskTarget again = far;
      again.received_ns = common::SteadyNowNs();
      desk.Post(again);
    }
    desk.Read(k * kDt_s, r);
    ASSERT_TRUE(r.valid) << "step " << k;
    for (int i = 0; i < kFingers; ++i) {
      const Eigen::Vector3d v = (r.p_WE[i] - prev[i]) / kDt_s;
      max_speed = std::max(max_speed, v.norm());
      max_acceleration = std::max(max_acceleration, (v - v_prev[i]).norm() / kDt_s);
      v_prev[i] = v;
      prev[i] = r.p_WE[i];
    }
  }
  const double bound = MaxFingertipSpeed(desk.config());
  EXPECT_LE(bound, 0.6);
  EXPECT_LE(max_speed, bound * (1.0 + 1e-9));
  EXPECT_GT(max_speed, 0.5 * bound) << "the speed bound is what limited this step";
  // Base 12 m/s^2 + turn 20 rad/s^2 x 0.16 m + closure 20 /s^2 x 0.065 m + centripetal 1.2^2 x
  // 0.16 m, about 16.7 m/s^2; 18 allows for the discrete steps.
  EXPECT_LE(max_acceleration, 18.0);
  EXPECT_NEAR(r.p_WH.x(), 0.3, 1e-4);
  EXPECT_NEAR(r.p_WH.y(), 0.3, 1e-4);
  EXPECT_NEAR(r.p_WH.z(), 0.0, 1e-4);
  const Eigen::Quaterniond q(r.q_WH_wxyz[0], r.q_WH_wxyz[1], r.q_WH_wxyz[2], r.q_WH_wxyz[3]);
  EXPECT_NEAR(q.angularDistance(Eigen::Quaterniond(Eigen::AngleAxisd(1.5, Eigen::Vector3d::UnitZ()))), 0.0, 1e-4);
  const Eigen::Matrix3d R = q.toRotationMatrix();
  for (int i = 0; i < kFingers; ++i) {
    EXPECT_LT((r.p_WE[i] - (r.p_WH + R * DeskFingertip_H(i, 1.0))).norm(), 1e-4) << "finger " << i;
  }
}

// The hand closes around what is under it: at closure c every fingertip is on a ring of radius
// 75 - 65 c mm about the grasp centre, so a ball there is held at one closure by all five.
TEST(DeskDevice, TheHandClosesAroundABall) {
  const Eigen::Vector3d centre(0.0, kDeskGraspCentreY_m, kDeskGraspCentreZ_m);
  const double ball_m = 0.04 + kSimFingertipRadius_m;  // the Moon's ball, touched by a fingertip
  const double c = (kDeskRingOpen_m - ball_m) / (kDeskRingOpen_m - kDeskRingClosed_m);
  for (int i = 0; i < kFingers; ++i) {
    EXPECT_NEAR((DeskFingertip_H(i, 0.0) - centre).norm(), kDeskRingOpen_m, 1e-12);
    EXPECT_NEAR((DeskFingertip_H(i, c) - centre).norm(), ball_m, 1e-12) << "finger " << i;
    EXPECT_LT(DeskFingertip_H(i, c).z(), centre.z()) << "below the equator, to hold it up";
  }
  EXPECT_LT(DeskFingertip_H(0, 0.0).y(), centre.y()) << "the thumb is on the person's side";
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (int i = 0; i < kFingers; ++i) sum += DeskFingertip_H(i, 0.5) - centre;
  EXPECT_LT(sum.head<2>().norm(), 1e-12) << "the pushes cancel sideways";
}

TEST(DeskDevice, OneFingerClosesAlone) {
  DeskDevice desk;
  DeskTarget t = Target(Eigen::Vector3d(0, 0, 0.1), 0.0);
  desk.Post(t);
  DeviceReading r;
  desk.Read(0.0, r);
  const auto open = r.p_WE;
  t.closure[1] = 1.0;  // the index finger
  t.received_ns = common::SteadyNowNs();
  desk.Post(t);
  for (int k = 1; k <= 2000; ++k) desk.Read(k * kDt_s, r);
  for (int i = 0; i < kFingers; ++i) {
    if (i == 1) {
      EXPECT_GT((r.p_WE[i] - open[i]).norm(), 0.03);
    } else {
      EXPECT_LT((r.p_WE[i] - open[i]).norm(), 1e-12) << "finger " << i;
    }
  }
}

std::uint64_t g_fake_now_ns = 0;
std::uint64_t FakeNow() { return g_fake_now_ns; }

TEST(DeskDevice, GoesInvalidWhenTheInputStops) {
  DeskDevice desk;
  desk.SetClockForTest(&FakeNow);
  g_fake_now_ns = 5'000'000'000;
  DeskTarget t = Target(Eigen::Vector3d(0, 0, 0.1), 0.0);
  t.received_ns = g_fake_now_ns;
  desk.Post(t);
  DeviceReading r;
  desk.Read(0.0, r);
  EXPECT_TRUE(r.valid);
  g_fake_now_ns += 900'000'000;  // 0.9 s of silence: still the person's hand
  desk.Read(0.9, r);
  EXPECT_TRUE(r.valid);
  g_fake_now_ns += 200'000'000;  // 1.1 s: the desk has gone quiet
  desk.Read(1.1, r);
  EXPECT_FALSE(r.valid);
  t.received_ns = g_fake_now_ns;  // input again: the hand is back
  desk.Post(t);
  desk.Read(1.101, r);
  EXPECT_TRUE(r.valid);
}

TEST(DeskDevice, GoesInvalidWhenTheWindowLosesFocus) {
  DeskDevice desk;
  desk.Post(Target(Eigen::Vector3d(0, 0, 0.1), 0.0));
  DeviceReading r;
  desk.Read(0.0, r);
  EXPECT_TRUE(r.valid);
  desk.Post(Target(Eigen::Vector3d(0, 0, 0.1), 0.0, 0.0, /*focused=*/false));
  desk.Read(0.001, r);
  EXPECT_FALSE(r.valid);
}

// A hand pressing on the table when the window loses focus: the loop releases it the way it
// releases a lost device, its force ramped to zero by the safety stage, not cut.
TEST(DeskDevice, LosingFocusWhilePressingRampsTheForceToZero) {
  DeskDevice desk;
  HapticLoop loop(desk, HapticLoopConfig{1000.0, false});
  loop.SetRenderer(std::make_shared<Floor>());
  double t_s = 0.0;
  for (int i = 0; i < 1000; ++i, t_s += kDt_s) {
    desk.Post(Target(Eigen::Vector3d(0, -0.1, 0.005), 0.0));
    loop.Step(t_s);
  }
  double pressing_N = 0.0;
  for (const auto& f : loop.safety_output().f_E_W) pressing_N += f.z();
  ASSERT_GT(pressing_N, 5.0);
  double previous_N = pressing_N;
  int steps_to_zero = -1;
  for (int i = 0; i < 100; ++i, t_s += kDt_s) {
    desk.Post(Target(Eigen::Vector3d(0, -0.1, 0.005), 0.0, 0.0, /*focused=*/false));
    loop.Step(t_s);
    double now_N = 0.0;
    for (const auto& f : loop.safety_output().f_E_W) now_N += f.z();
    EXPECT_LT(now_N, previous_N + 1e-12) << "step " << i;
    EXPECT_LT(previous_N - now_N, 0.5 * pressing_N) << "a ramp, not a cut, at step " << i;
    previous_N = now_N;
    if (now_N == 0.0 && steps_to_zero < 0) steps_to_zero = i;
  }
  EXPECT_GE(steps_to_zero, 2);
  EXPECT_LE(steps_to_zero, 25);  // the safety's fault ramp: 20 ms
  EXPECT_GT(loop.faults(), 0u);
}

TEST(DeskDevice, ReadDoesNotAllocate) {
  DeskDevice desk;
  DeskTarget t = Target(Eigen::Vector3d(0, 0, 0.1), 0.0);
  desk.Post(t);
  DeviceReading r;
  desk.Read(0.0, r);
  const long before = testing::AllocationCount();
  for (int k = 1; k < 2000; ++k) {
    t.p_WH_m[0] = 0.1 * std::sin(k * 0.01);
    desk.Post(t);
    desk.Read(k * kDt_s, r);
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
}

}  // namespace
}  // namespace handshare::haptic
