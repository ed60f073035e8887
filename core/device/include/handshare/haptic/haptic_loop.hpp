#pragma once
/// The haptic loop: its own thread at a fixed rate (1 kHz default, up to 4 kHz and more),
/// absolute deadlines, overrun counting and re-sync. Each Step(): read device -> check data
/// -> force renderer (contacts, controls) -> force safety (clamp, rate bound, passivity,
/// fault ramp) -> command device -> publish a snapshot for the bridge thread through a
/// lock-free triple buffer. Step() never allocates, locks or does I/O.
///
/// The renderer is swapped by the bridge thread (scene change) without a lock: SetRenderer()
/// posts it, the next Step() adopts it, and the bridge frees a replaced renderer only after
/// the haptic thread has confirmed that it let go of it (CollectRetired()).
///
/// Renderer hand-over. Invariant: the bridge frees a posted renderer only when the haptic
/// thread never took it, or when every use the haptic thread made of it happens-before the
/// free. Why it holds:
///  1. pending_ is a one-slot mailbox written only by exchanges: SetRenderer() exchanges the
///     new renderer in (release; "no renderer" is posted as a marker, so nullptr means empty),
///     Step() exchanges nullptr in when a relaxed load saw the slot full (only Step() empties
///     it, so it is still full; acquire: the renderer's construction happens-before its use).
///     The exchanges of one atomic form one modification order in which each reads the value
///     the one before it wrote, so every posted renderer is taken out exactly once: by Step()
///     (adopted), or by the bridge's next SetRenderer(), which gets it back untouched by the
///     haptic thread and frees it at once.
///  2. The bridge numbers the renderers it posts 1, 2, ..., giving the number of one it gets
///     back to the next. Its exchanges are sequenced, so they sit in posting order in the
///     modification order, and Step() takes renderers in that order: renderer k is the k-th
///     the haptic thread takes.
///  3. adopted_ (written only by Step(), release) counts the takes; Step() stores k after it
///     switched renderer_ to renderer k, and renderer_ only moves on to later takes. So the
///     haptic thread used renderers below k only before that store, and never after it.
///  4. CollectRetired() reads n = adopted_ (acquire) and frees only renderers numbered below
///     n. Its load reads the release store of n, so every use of those renderers happens-before
///     the free (3). Renderer n, in use, and later ones (posted, or taken but not yet counted:
///     the window the test hook widens) stay owned.
/// Step() costs one relaxed load when nothing is posted, and an exchange and a store when it
/// adopts: lock-free, no allocation.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
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
  /// The most periods one step advances the haptic world by. A step that follows a stall (the
  /// loop's schedule re-syncs after 5 late periods, common::PeriodicLoop) would otherwise hold
  /// the fingers' forces on the bodies for the whole stall: 3.5 N on a held 0.2 kg ball over
  /// 100 ms throws it out of the hand. The world then lags the wall clock by the stall; the
  /// force impulse the user felt is still taken over the true time.
  int max_world_step_periods = 5;
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
  /// The loop keeps it alive until the haptic thread confirmed that it let go of it; not
  /// real-time. Call it (and CollectRetired) from one thread only.
  void SetRenderer(std::shared_ptr<ForceRenderer> renderer);
  /// Bridge side: frees renderers the haptic thread confirmed it no longer uses. Not real-time.
  void CollectRetired();
  /// Tests only: Step() calls hook(arg) while it adopts a posted renderer, between taking it
  /// and counting it in adopted_, to widen that window in stress tests. Set it before
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
  /// Faulted steps by cause (a step counts under each cause it had), so that a fault in a long
  /// session says what it was: "device reading invalid 3, fingertip jump 1". Empty when there
  /// were none.
  std::string FaultCauses() const;
  /// Steps in which the safety's rate bound cut a finger's force change (a step in what the
  /// world renders: a peer's contact appearing or vanishing at once, a body thrown).
  std::uint64_t rate_limited_steps() const noexcept { return rate_limited_steps_.load(std::memory_order_relaxed); }

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
  // Renderer hand-over (see the top of this file). pending_: the mailbox, nullptr when empty.
  // adopted_: how many renderers the haptic thread has taken (it uses the newest). renderer_:
  // the one it uses (haptic thread only). posted_ and numbered_ (bridge only): the renderers
  // posted and not yet freed, by number, and the number of the newest.
  struct Posted {
    std::shared_ptr<ForceRenderer> renderer;
    std::uint64_t number;
  };
  std::atomic<ForceRenderer*> pending_{nullptr};
  std::atomic<std::uint64_t> adopted_{0};
  ForceRenderer* renderer_ = nullptr;
  std::vector<Posted> posted_;
  std::uint64_t numbered_ = 0;
  void (*adoption_hook_)(void*) noexcept = nullptr;  // tests only: see SetAdoptionHookForTest
  void* adoption_hook_arg_ = nullptr;
  std::uint64_t seq_ = 0;
  std::array<Eigen::Vector3d, kFingers> impulse_E_W_Ns_{};  // haptic thread only
  common::TripleBuffer<HapticSnapshot> snapshots_;
  // Heap-held: LoopStats is about 16 KB; three copies live in the buffer.
  std::unique_ptr<common::TripleBuffer<common::LoopStats>> stats_holder_ =
      std::make_unique<common::TripleBuffer<common::LoopStats>>();
  common::TripleBuffer<common::LoopStats>& stats_ = *stats_holder_;
  std::atomic<bool> running_{false};
  std::atomic<std::uint64_t> faults_{0};
  // Causes, in FaultCauses()'s order: the device's reading invalid, not finite, stale; the
  // safety's not finite, out of range, jump. Written only on faulted steps.
  static constexpr int kFaultCauses = 6;
  std::array<std::atomic<std::uint64_t>, kFaultCauses> fault_causes_{};
  std::atomic<std::uint64_t> rate_limited_steps_{0};
  std::thread thread_;
};

}  // namespace handshare::haptic
