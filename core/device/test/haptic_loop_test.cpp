#include "handshare/haptic/haptic_loop.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <deque>
#include <limits>
#include <memory>
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
  // Until 20 snapshots were taken, not for a fixed time: on a loaded machine the haptic thread
  // may not run at all for 300 ms (seen: 0 snapshots then). The deadline only bounds a failure.
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (seen < 20 && std::chrono::steady_clock::now() < end) {
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
  EXPECT_EQ(seen, 20u);
  EXPECT_GE(stats.steps, last);  // every handed-off snapshot was a counted step
  EXPECT_GT(stats.jitter.count(), 0u);
}

/// A renderer that asks every fingertip for a fixed force.
class ConstantRenderer final : public ForceRenderer {
 public:
  explicit ConstantRenderer(Eigen::Vector3d f) : f_(f) {}
  void Render(double, double dt_s, std::uint64_t, const DeviceReading&, std::array<Eigen::Vector3d, kFingers>& out) noexcept override {
    for (auto& f : out) f = f_;
    ++renders;
    last_dt_s = dt_s;
  }
  void ReleaseAll() noexcept override { ++releases; }
  Eigen::Vector3d f_;
  int renders = 0, releases = 0;
  double last_dt_s = 0.0;
};

// After a stall (here 100 ms between two steps) the world advances by at most
// max_world_step_periods periods: the fingers' forces are not held on the bodies for the whole
// stall (core/contact grasp_test: that throws a held ball). The impulse the user felt is the
// force over the true time.
TEST(HapticLoop, AStepAfterAStallAdvancesTheWorldByAtMostFivePeriods) {
  FakeDevice device;
  HapticLoopConfig config{1000.0, false};
  config.safety.passivity = false;
  config.stale_after_s = 1.0;
  HapticLoop loop(device, config);
  auto renderer = std::make_shared<ConstantRenderer>(Eigen::Vector3d(0, 0, 1.0));
  loop.SetRenderer(renderer);
  for (int k = 0; k < 300; ++k) loop.Step(k * 1e-3);  // up to 1 N through the rate bound
  EXPECT_DOUBLE_EQ(renderer->last_dt_s, 1e-3);
  HapticSnapshot before, after;
  ASSERT_TRUE(loop.TakeSnapshot(before));
  loop.Step(0.299 + 0.1);
  EXPECT_DOUBLE_EQ(renderer->last_dt_s, 5e-3);
  ASSERT_TRUE(loop.TakeSnapshot(after));
  EXPECT_NEAR(after.impulse_E_W_Ns[0][2] - before.impulse_E_W_Ns[0][2], 1.0 * 0.1, 1e-9);
  loop.Step(0.399 + 0.003);  // a late step below the bound is taken whole
  EXPECT_NEAR(renderer->last_dt_s, 3e-3, 1e-12);
}

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

// The snapshot's impulse is the sum of every step's commanded force times the time it was held,
// so a window's mean force comes out exact however unevenly the steps (or the bridge's samples
// of them) are spaced: here steps of 1 ms and a stall of 40 ms, with the force stepping.
TEST(HapticLoop, SnapshotImpulseIsTheForceHeldOverEveryStep) {
  FakeDevice device;
  HapticLoopConfig config{1000.0, false};
  config.safety.passivity = false;
  config.safety.max_force_rate_N_per_s = 1e9;  // outputs equal the demands
  HapticLoop loop(device, config);
  auto renderer = std::make_shared<ConstantRenderer>(Eigen::Vector3d(0, 0, 1.0));
  loop.SetRenderer(renderer);
  std::vector<double> times;
  for (int k = 0; k <= 100; ++k) times.push_back(k * 1e-3);
  times.push_back(0.140);  // a stall: the 1 N force was held for 40 ms
  for (int k = 1; k <= 50; ++k) times.push_back(0.140 + k * 1e-3);
  double expected_z = 0.0;
  double held_z = 0.0;  // the force commanded at the previous step
  double last_t = -1.0;
  for (double t : times) {
    if (last_t >= 0.0) expected_z += held_z * (t - last_t);
    loop.Step(t);
    held_z = device.last[1].z();
    last_t = t;
  }
  HapticSnapshot s;
  ASSERT_TRUE(loop.TakeSnapshot(s));
  EXPECT_NEAR(expected_z, 0.190, 1e-12);  // 1 N over 0.190 s (the first step commands from t = 0)
  for (int i = 0; i < kFingers; ++i) {
    EXPECT_NEAR(s.impulse_E_W_Ns[i][2], expected_z, 1e-12) << "finger " << i;
    EXPECT_EQ(s.impulse_E_W_Ns[i][0], 0.0);
  }
}

// Data older than stale_after_s is a fault even when it claims to be valid.
class StaleDevice final : public Device {
 public:
  DeviceCapabilities capabilities() const noexcept override { return {}; }
  void Read(double, DeviceReading& out) noexcept override {
    out.valid = true;
    out.stamp_ns = common::SteadyNowNs() - age_ns;
    for (auto& p : out.p_WE) p = Eigen::Vector3d(0.01, 0.02, 0.03 + shift_m);
  }
  void Command(const std::array<Eigen::Vector3d, kFingers>&) noexcept override {}
  const char* name() const noexcept override { return "stale"; }
  std::uint64_t age_ns = 0;
  double shift_m = 0.0;  // every fingertip moved this far along z
};

TEST(HapticLoop, StaleDeviceDataIsAFault) {
  StaleDevice device;
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  loop.Step(0.0);
  EXPECT_EQ(loop.faults(), 0u);
  EXPECT_EQ(loop.FaultCauses(), "");
  device.age_ns = 200'000'000;  // 0.2 s old, limit 0.05 s
  loop.Step(0.001);
  EXPECT_EQ(loop.faults(), 1u);
  EXPECT_EQ(loop.FaultCauses(), "device reading stale 1");
}

// A loop that stalled 40 ms (a busy machine) reads a fingertip that moved 10 mm meanwhile:
// motion at 0.25 m/s, no fault. The same 10 mm from one step to the next is a jump.
TEST(HapticLoop, AFingertipThatMovedThroughAStallIsNotAFault) {
  StaleDevice device;
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  loop.Step(0.0);
  device.shift_m = 0.010;
  loop.Step(0.040);
  EXPECT_EQ(loop.faults(), 0u) << loop.FaultCauses();
  device.shift_m = 0.020;
  loop.Step(0.041);
  EXPECT_EQ(loop.faults(), 1u);
  EXPECT_EQ(loop.FaultCauses(), "fingertip jump 1");
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

/// Counts of the hand-over stress test's renderers, shared by both threads.
struct RendererTally {
  std::atomic<long> created{0};
  std::atomic<long> freed{0};
  std::atomic<long> renders{0};
  std::atomic<long> used_after_free{0};
  std::atomic<long> double_frees{0};
};

/// A renderer with a canary: alive from construction until its owner frees it through
/// Free() (the deleter of the shared_ptr handed to the loop), which poisons the canary. Its
/// storage outlives the test's loop, so a late Render() reads the poisoned canary and counts a
/// use after free (no sanitizer needed). Free() does not run the destructor: that would reset
/// the vtable to the abstract base and turn a late call into a "pure virtual call" abort.
class CanaryRenderer final : public ForceRenderer {
 public:
  explicit CanaryRenderer(RendererTally& tally) : tally_(tally) { tally_.created.fetch_add(1, std::memory_order_relaxed); }
  void Render(double, double, std::uint64_t, const DeviceReading&, std::array<Eigen::Vector3d, kFingers>& out) noexcept override {
    Check();
    for (auto& f : out) f = Eigen::Vector3d(0, 0, 0.1);
    tally_.renders.fetch_add(1, std::memory_order_relaxed);
  }
  void ReleaseAll() noexcept override { Check(); }
  void Free() noexcept {
    if (canary_.exchange(kFreed, std::memory_order_relaxed) != kAlive) {
      tally_.double_frees.fetch_add(1, std::memory_order_relaxed);
    }
    tally_.freed.fetch_add(1, std::memory_order_relaxed);
  }

 private:
  static constexpr std::uint64_t kAlive = 0xA11FE0A11FE0A11Full;
  static constexpr std::uint64_t kFreed = 0xDEADBEEFDEADBEEFull;
  void Check() noexcept {
    if (canary_.load(std::memory_order_relaxed) != kAlive) {
      tally_.used_after_free.fetch_add(1, std::memory_order_relaxed);
    }
  }
  RendererTally& tally_;
  std::atomic<std::uint64_t> canary_{kAlive};
};

/// How the two threads of the stress test pace each other.
struct SwapPacing {
  std::atomic<long> swaps_in_window{0};  // bridge: swaps begun and finished in an open window
  std::atomic<bool> bridge_done{false};
  std::atomic<long> steps_done{0};     // haptic thread: steps finished
  std::atomic<long> windows{0};        // haptic thread: adoption windows entered
  std::atomic<bool> in_window{false};  // haptic thread: inside an adoption window now
};

/// Holds the haptic thread inside the adoption window until the bridge has done a whole swap
/// (SetRenderer and CollectRetired) in it, or 200 us have passed.
void WidenAdoptionWindow(void* arg) noexcept {
  auto& pacing = *static_cast<SwapPacing*>(arg);
  const long seen = pacing.swaps_in_window.load(std::memory_order_acquire);
  pacing.windows.fetch_add(1, std::memory_order_relaxed);
  pacing.in_window.store(true, std::memory_order_release);
  const auto until = std::chrono::steady_clock::now() + std::chrono::microseconds(200);
  while (pacing.swaps_in_window.load(std::memory_order_acquire) == seen &&
         !pacing.bridge_done.load(std::memory_order_acquire) && std::chrono::steady_clock::now() < until) {
    std::this_thread::yield();
  }
  pacing.in_window.store(false, std::memory_order_release);
}

// The bridge swaps renderers 100,000 times, as the node does (SetRenderer, then CollectRetired),
// while the haptic thread steps as fast as it can and the hook holds it inside the adoption
// window: no renderer is used after the loop let it be freed, and none leaks. After each swap
// the bridge waits (up to 1 ms) for a step, or for a window to swap in, so that swaps meet steps.
TEST(HapticLoop, RendererSwapsUnderStressNeverFreeARendererInUse) {
  constexpr long kSwaps = 100'000;
  RendererTally tally;
  std::deque<CanaryRenderer> storage;  // outlives the loop: see CanaryRenderer
  FakeDevice device;
  auto loop = std::make_unique<HapticLoop>(device, HapticLoopConfig{1000.0, false});
  SwapPacing pacing;
  loop->SetAdoptionHookForTest(&WidenAdoptionWindow, &pacing);

  std::thread haptic([&] {
    double t_s = 0.0;
    while (!pacing.bridge_done.load(std::memory_order_acquire)) {
      loop->Step(t_s += 1e-3);
      pacing.steps_done.fetch_add(1, std::memory_order_release);
    }
  });
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i < kSwaps; ++i) {
    const long steps = pacing.steps_done.load(std::memory_order_acquire);
    const bool in_window = pacing.in_window.load(std::memory_order_acquire);
    if (i % 64 == 63) {
      loop->SetRenderer(nullptr);
    } else {
      CanaryRenderer& r = storage.emplace_back(tally);
      loop->SetRenderer(std::shared_ptr<ForceRenderer>(&r, [](ForceRenderer* p) { static_cast<CanaryRenderer*>(p)->Free(); }));
    }
    loop->CollectRetired();
    if (in_window) pacing.swaps_in_window.fetch_add(1, std::memory_order_release);
    const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(1);
    while (pacing.steps_done.load(std::memory_order_acquire) == steps &&
           (in_window || !pacing.in_window.load(std::memory_order_acquire)) &&
           std::chrono::steady_clock::now() < until) {
      std::this_thread::yield();
    }
  }
  pacing.bridge_done.store(true, std::memory_order_release);
  haptic.join();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  EXPECT_EQ(tally.used_after_free.load(), 0) << "renders or releases on a freed renderer";
  EXPECT_EQ(tally.double_frees.load(), 0);
  EXPECT_GT(tally.renders.load(), 0);
  EXPECT_GT(pacing.windows.load(), kSwaps / 100) << "few swaps met an adoption window";
  loop->Step(0.0);  // adopts the last post if the haptic thread stopped before it
  loop->CollectRetired();
  EXPECT_LE(tally.created.load() - tally.freed.load(), 1) << "only the one in use stays owned";
  loop.reset();
  EXPECT_EQ(tally.created.load(), kSwaps - kSwaps / 64);
  EXPECT_EQ(tally.freed.load(), tally.created.load()) << "every renderer is freed with the loop";
  std::printf("%ld swaps in %.2f s: %ld steps, %ld adoption windows, %ld renders\n", kSwaps, seconds,
              pacing.steps_done.load(), pacing.windows.load(), tally.renders.load());
}

}  // namespace
}  // namespace handshare::haptic
