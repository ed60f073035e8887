#pragma once
/// Timing of a fixed-rate loop with absolute deadlines (STYLE: real-time rules 4):
/// wake at next += period, count overruns, re-sync instead of bursting after a stall,
/// and keep wake-up jitter and step durations in allocation-free histograms.
#include <chrono>
#include <cstdint>

#include "handshare/common/latency_histogram.hpp"

namespace handshare::common {

struct LoopStats {
  double rate_Hz = 0.0;  // achieved steps per second since start
  std::uint64_t steps = 0;
  std::uint64_t overruns = 0;  // steps that finished after their next deadline
  std::uint64_t resyncs = 0;   // times the schedule was reset after falling far behind
  LatencyHistogram jitter;     // wake-up time minus deadline [us]
  LatencyHistogram step;       // step duration [us]
};

class PeriodicLoop {
 public:
  using Clock = std::chrono::steady_clock;

  /// @param period  loop period, e.g. 1 ms for 1 kHz.
  /// @param resync_after  fall this many periods behind and the schedule restarts from now.
  explicit PeriodicLoop(std::chrono::nanoseconds period, int resync_after = 5) noexcept;

  /// Sleeps until the next deadline, records jitter; returns the wake-up time.
  Clock::time_point WaitNext() noexcept;
  /// Records the end of the step started at the last WaitNext().
  void EndStep() noexcept;

  std::chrono::nanoseconds period() const noexcept { return period_; }
  const LoopStats& stats() const noexcept { return stats_; }

 private:
  std::chrono::nanoseconds period_;
  int resync_after_;
  Clock::time_point start_;
  Clock::time_point next_;
  Clock::time_point woke_;
  LoopStats stats_;
};

/// Seconds of a steady-clock duration as double.
inline double ToSeconds(std::chrono::nanoseconds d) noexcept { return d.count() * 1e-9; }

}  // namespace handshare::common
