#pragma once
/// The haptic loop: its own thread at a fixed rate (1 kHz default, up to 4 kHz and more),
/// absolute deadlines, overrun counting and re-sync. Each Step(): read device -> (contact
/// rendering, later layers) -> clamp forces -> command device -> publish a snapshot for the
/// bridge thread through a lock-free triple buffer. Step() never allocates, locks or does I/O.
#include <atomic>
#include <cstdint>
#include <memory>
#include <thread>

#include "handshare/common/periodic_loop.hpp"
#include "handshare/common/triple_buffer.hpp"
#include "handshare/haptic/device.hpp"

namespace handshare::haptic {

/// Fixed-size, trivially copyable: what the haptic thread hands to the bridge thread.
struct HapticSnapshot {
  std::uint64_t seq = 0;
  std::uint64_t stamp_ns = 0;
  double t_s = 0.0;
  double p_WH_m[3] = {};
  double q_WH_wxyz[4] = {1, 0, 0, 0};
  double p_WE_m[kFingers][3] = {};
  double f_E_W_N[kFingers][3] = {};
  double fingertip_radius_m = 0.0;
  bool fault = false;
};

struct HapticLoopConfig {
  double rate_Hz = 1000.0;
  bool realtime_priority = true;  // try SCHED_FIFO; carry on without it if not permitted
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

  /// One step at time t_s since start. Public for tests; the thread calls it. Real-time safe.
  void Step(double t_s) noexcept;

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
