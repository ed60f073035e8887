#include "handshare/haptic/haptic_loop.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <limits>
#include <new>
#include <thread>

#include "handshare/haptic/sim_hand.hpp"

// Counts every heap allocation in this test binary, so a test can assert that the haptic
// step allocates nothing.
namespace {
std::atomic<long> g_allocations{0};
}
void* operator new(std::size_t n) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(n ? n : 1)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }

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
  const long before = g_allocations.load();
  for (int i = 0; i < 10000; ++i) loop.Step(i * 1e-3);
  EXPECT_EQ(g_allocations.load() - before, 0);
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

}  // namespace
}  // namespace handshare::haptic
