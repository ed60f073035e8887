#pragma once
/// The haptic loop: its own thread at a fixed rate (1 kHz default, up to 4 kHz and more),
/// absolute deadlines, overrun counting and re-sync. Each Step(): read device -> check data
/// -> force renderer (contacts, controls) -> force safety (clamp, rate bound, passivity,
/// fault ramp) -> command device -> publish a snapshot for the bridge thread through a
/// lock-free triple buffer. Step() never allocates, locks or does I/O.
///
/// The renderer is swapped by the bridge thread (scene change) without a lock: SetRenderer()
/// posts it, the next Step() adopts it, and the bridge frees a replaced renderer only after
/// the haptic thread has let go of it (CollectRetired()).
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>
#include <vector>

#include "handshare/common/periodic_loop.hpp"
#include "handshare/common/triple_buffer.hpp"
#include "handshare/haptic/device.hpp"
#include "handshare/haptic/force_renderer.hpp"
#include "handshare/haptic/force_safety.hpp"
#include "handshare/haptic/haptic_snapshot.hpp"

namespace handshare::haptic {

struct HapticLoopConfig {
  double rate_Hz = 1000.0;
  bool realtime_priority = true;  // try SCHED_FIFO; carry on without it if not permitted
  /// Safety stage settings; its period and max force come from rate_Hz and the device.
  ForceSafetyConfig safety{};
  /// A device reading older than this is stale: a fault [s].
  double stale_after_s = 0.05;
};

class HapticLoop {
 public:
  HapticLoop(Device& device, HapticLoopConfig config);
  ~HapticLoop();
  HapticLoop(const HapticLoop&) = delete;
  HapticLoop& operator=(const HapticLoop&) = delete;

  /// Starts the haptic thread. Returns false if real-time priority was asked for but refused
  /// (the loop runs anyway at normal priority).
  bool Start();
  /// Stops and joins the haptic thread (idempotent).
  void Stop();

  /// Time on the loop's clock (the t_s of Step) now [s]; after Start().
  double now_s() const noexcept;

  /// One step at time t_s since start. Public for tests; the thread calls it. Real-time safe.
  void Step(double t_s) noexcept;

  /// Bridge side: the renderer the loop uses from its next step on (nullptr: no forces).
  /// The loop keeps it alive; not real-time.
  void SetRenderer(std::shared_ptr<ForceRenderer> renderer);
  /// Bridge side: frees renderers the haptic thread no longer uses. Not real-time.
  void CollectRetired();
  /// Tests only: Step() calls hook(arg) while it adopts a posted renderer, between taking it
  /// and telling the bridge it uses it, to widen that window in stress tests. Set it before
  /// any thread calls Step(); nullptr (the default) turns it off at the cost of one load.
  /// The hook runs on the haptic thread; not real-time.
  void SetAdoptionHookForTest(void (*hook)(void*) noexcept, void* arg) noexcept {
    adoption_hook_ = hook;
    adoption_hook_arg_ = arg;
  }
  /// Safety status of the last step (haptic thread; tests).
  const ForceSafetyOutput& safety_output() const noexcept { return safety_out_; }

  /// Bridge side: newest snapshot, if a new one exists.
  bool TakeSnapshot(HapticSnapshot& out) noexcept { return snapshots_.Read(out); }
  /// Bridge side: loop statistics, refreshed about 10 times a second by the haptic thread.
  bool TakeStats(common::LoopStats& out) noexcept { return stats_.Read(out); }
  std::uint64_t faults() const noexcept { return faults_.load(std::memory_order_relaxed); }

 private:
  void ThreadMain();

  Device& device_;
  HapticLoopConfig config_;
  DeviceCapabilities caps_;
  DeviceReading reading_;
  std::array<Eigen::Vector3d, kFingers> f_E_W_{};
  ForceSafety safety_;
  ForceSafetyInput safety_in_;
  ForceSafetyOutput safety_out_;
  double last_t_s_ = -1.0;
  common::PeriodicLoop::Clock::time_point start_{};  // set by Start() before the thread runs
  // Renderer hand-over: pending_ is posted by the bridge, adopted by the haptic thread, which
  // publishes what it uses in in_use_; owned_ (bridge only) keeps every posted renderer alive
  // until it is neither pending nor in use.
  std::atomic<ForceRenderer*> pending_{nullptr};
  std::atomic<ForceRenderer*> in_use_{nullptr};
  std::atomic<bool> has_pending_{false};
  ForceRenderer* renderer_ = nullptr;
  std::vector<std::shared_ptr<ForceRenderer>> owned_;
  void (*adoption_hook_)(void*) noexcept = nullptr;  // tests only: see SetAdoptionHookForTest
  void* adoption_hook_arg_ = nullptr;
  std::uint64_t seq_ = 0;
  common::TripleBuffer<HapticSnapshot> snapshots_;
  // Heap-held: LoopStats is about 16 KB; three copies live in the buffer.
  std::unique_ptr<common::TripleBuffer<common::LoopStats>> stats_holder_ =
      std::make_unique<common::TripleBuffer<common::LoopStats>>();
  common::TripleBuffer<common::LoopStats>& stats_ = *stats_holder_;
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> faults_{0};
  std::thread thread_;
};

}  // namespace handshare::haptic
