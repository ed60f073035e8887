#include "handshare/haptic/haptic_loop.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <thread>
#include <vector>

#include "handshare/common/clock.hpp"
#include "handshare/haptic/sim_hand.hpp"
#include "handshare/testing/allocation_counter.hpp"

namespace handshare::haptic {
namespace {

/// A device whose readings can be corrupted, and which returns a fixed force demand.
class FakeDevice final : public Device {
 public:
  DeviceCapabilities capabilities() const noexcept override { return {}; }
  void Read(double, DeviceReading& out) noexcept override {
    out.valid = valid;
    out.p_WH = Eigen::Vector3d(0, 0, bad_value);
    for (auto& p : out.p_WE) p = Eigen::Vector3d(0.01, 0.02, 0.03);
  }
  void Command(const std::array<Eigen::Vector3d, kFingers>& f) noexcept override { last = f; }
  const char* name() const noexcept override { return "fake"; }
  bool valid = true;
  double bad_value = 0.0;
  std::array<Eigen::Vector3d, kFingers> last{};
};

TEST(HapticLoop, StepDoesNotAllocate) {
  SimDevice device(HandScript::Parse("start 0 0 0.1\nmove 1 0.1 0 0.1 grip 1\n", "t"));
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  loop.Step(0.0);  // warm-up outside the measured window
  const long before = testing::AllocationCount();
  for (int i = 0; i < 10000; ++i) loop.Step(i * 1e-3);
  EXPECT_EQ(testing::AllocationCount() - before, 0);
}

TEST(HapticLoop, SnapshotCarriesFingertipsOfTheScriptedHand) {
  SimDevice device(HandScript::Parse("start 0.1 0.2 0.3 grip 0\n", "t"));
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  loop.Step(0.5);
  HapticSnapshot s;
  ASSERT_TRUE(loop.TakeSnapshot(s));
  const auto expected = SimFingertips(HandPose{Eigen::Vector3d(0.1, 0.2, 0.3), 0.0});
  for (int i = 0; i < kFingers; ++i) {
    for (int k = 0; k < 3; ++k) EXPECT_DOUBLE_EQ(s.p_WE_m[i][k], expected[i][k]);
  }
  EXPECT_FALSE(s.fault);
  EXPECT_EQ(s.seq, 1u);
}

TEST(HapticLoop, InvalidOrNonFiniteDeviceDataIsAFaultWithZeroForce) {
  FakeDevice device;
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  device.bad_value = std::numeric_limits<double>::quiet_NaN();
  loop.Step(0.0);
  HapticSnapshot s;
  ASSERT_TRUE(loop.TakeSnapshot(s));
  EXPECT_TRUE(s.fault);
  for (const auto& f : device.last) EXPECT_TRUE(f.isZero());
  device.bad_value = 0.0;
  device.valid = false;
  loop.Step(0.001);
  ASSERT_TRUE(loop.TakeSnapshot(s));
  EXPECT_TRUE(s.fault);
  EXPECT_EQ(loop.faults(), 2u);
  for (const auto& p : s.p_WE_m) EXPECT_EQ(p[2], 0.0);  // a fault publishes no stale pose
}

TEST(HapticLoop, ThreadRunsAndHandsOffMonotonicSnapshots) {
  SimDevice device(HandScript::Parse("start 0 0 0\nmove 1 0.1 0 0\n", "t"));
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  loop.Start();
  std::uint64_t last = 0, seen = 0;
  HapticSnapshot s;
  const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(300);
  while (std::chrono::steady_clock::now() < end) {
    if (loop.TakeSnapshot(s)) {
      EXPECT_GT(s.seq, last);
      last = s.seq;
      ++seen;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  loop.Stop();
  common::LoopStats stats;
  ASSERT_TRUE(loop.TakeStats(stats));
  EXPECT_GT(seen, 0u);
  EXPECT_GE(stats.steps, last);  // every handed-off snapshot was a counted step
  EXPECT_GT(stats.jitter.count(), 0u);
}

/// A renderer that asks every fingertip for a fixed force.
class ConstantRenderer final : public ForceRenderer {
 public:
  explicit ConstantRenderer(Eigen::Vector3d f) : f_(f) {}
  void Render(double, double, const DeviceReading&, std::array<Eigen::Vector3d, kFingers>& out) noexcept override {
    for (auto& f : out) f = f_;
    ++renders;
  }
  void ReleaseAll() noexcept override { ++releases; }
  Eigen::Vector3d f_;
  int renders = 0, releases = 0;
};

// A fault mid-contact (device lost) ramps the commanded force linearly to zero within the
// configured ramp time, not at once and not later; it comes back through the rate bound.
TEST(HapticLoop, FaultMidContactRampsForceToZeroWithinTheConfiguredTime) {
  FakeDevice device;
  HapticLoopConfig config{1000.0, false};
  config.safety.fault_ramp_time = std::chrono::milliseconds(20);
  config.safety.passivity = false;  // the fingertip does not move: nothing to observe
  HapticLoop loop(device, config);
  auto renderer = std::make_shared<ConstantRenderer>(Eigen::Vector3d(0, 0, 5.0));
  loop.SetRenderer(renderer);
  int k = 0;
  for (; k < 200; ++k) loop.Step(k * 1e-3);
  EXPECT_NEAR(device.last[1].z(), 3.5, 1e-12);  // clamped at the device's limit
  device.valid = false;
  std::vector<double> ramp;
  for (int j = 0; j < 30; ++j, ++k) {
    loop.Step(k * 1e-3);
    ramp.push_back(device.last[1].z());
  }
  EXPECT_GT(ramp[0], 0.5 * 3.5);  // no jump to zero: a ramp
  for (std::size_t j = 1; j < ramp.size(); ++j) EXPECT_LE(ramp[j], ramp[j - 1]);
  EXPECT_EQ(ramp[19], 0.0);  // zero within 20 steps of 1 ms
  EXPECT_GT(renderer->releases, 0);
  device.valid = true;
  loop.Step(k++ * 1e-3);
  // Back in through the rate bound, no jump to the full force.
  EXPECT_LE(device.last[1].z(), config.safety.max_force_rate_N_per_s * 1e-3 + 1e-12);
  EXPECT_LT(device.last[1].z(), 3.5);
  for (int j = 0; j < 100; ++j, ++k) loop.Step(k * 1e-3);
  EXPECT_NEAR(device.last[1].z(), 3.5, 1e-12);
}

// Data older than stale_after_s is a fault even when it claims to be valid.
class StaleDevice final : public Device {
 public:
  DeviceCapabilities capabilities() const noexcept override { return {}; }
  void Read(double, DeviceReading& out) noexcept override {
    out.valid = true;
    out.stamp_ns = common::SteadyNowNs() - age_ns;
    for (auto& p : out.p_WE) p = Eigen::Vector3d(0.01, 0.02, 0.03);
  }
  void Command(const std::array<Eigen::Vector3d, kFingers>&) noexcept override {}
  const char* name() const noexcept override { return "stale"; }
  std::uint64_t age_ns = 0;
};

TEST(HapticLoop, StaleDeviceDataIsAFault) {
  StaleDevice device;
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  loop.Step(0.0);
  EXPECT_EQ(loop.faults(), 0u);
  device.age_ns = 200'000'000;  // 0.2 s old, limit 0.05 s
  loop.Step(0.001);
  EXPECT_EQ(loop.faults(), 1u);
}

// The bridge swaps renderers while the loop runs; the old one is freed only after the
// haptic thread adopted the new one, and the step still allocates nothing.
TEST(HapticLoop, RendererSwapIsAdoptedAndTheOldOneFreedWithoutAllocationInTheStep) {
  FakeDevice device;
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  auto first = std::make_shared<ConstantRenderer>(Eigen::Vector3d(0, 0, 1.0));
  std::weak_ptr<ConstantRenderer> first_alive = first;
  loop.SetRenderer(std::move(first));
  loop.Step(0.0);
  if (auto alive = first_alive.lock()) {
    EXPECT_EQ(alive->renders, 1);
  } else {
    ADD_FAILURE() << "the renderer in use was freed";
  }
  loop.SetRenderer(std::make_shared<ConstantRenderer>(Eigen::Vector3d(0, 0, 2.0)));
  loop.CollectRetired();
  EXPECT_FALSE(first_alive.expired());  // the haptic thread has not let go yet
  const long before = testing::AllocationCount();
  for (int k = 1; k < 2000; ++k) loop.Step(k * 1e-3);
  EXPECT_EQ(testing::AllocationCount() - before, 0);
  loop.CollectRetired();
  EXPECT_TRUE(first_alive.expired());
  EXPECT_NEAR(device.last[0].z(), 2.0, 1e-12);
}

}  // namespace
}  // namespace handshare::haptic
