#pragma once
/// A node's loop as loop statistics (LoopStatistics, 1 Hz), for loops other than the haptic
/// loop (which has its own, common::PeriodicLoop): a graphics node's frames, an audio guide's
/// board loop. Per statistics period: passes per second, how late each pass began after it was
/// due (jitter) and how long its work took (step); since the start: the passes and the missed
/// ones (overruns: a pass that began a whole period or more after it was due, so at least one
/// pass of the rate did not happen). A loop without a period passes each pass as due when it
/// began (no jitter, no overruns). Not real-time: the loop's thread records and fills.
#include <chrono>
#include <cstdint>

#include "handshare/common/latency_histogram.hpp"
#include "handshare/dds/messages.hpp"

namespace handshare::dds {

class PassStatistics {
 public:
  using Clock = std::chrono::steady_clock;
  /// period: the loop's period (a graphics node's 1 / --fps); the first statistics period
  /// starts at `start`.
  PassStatistics(Clock::duration period, Clock::time_point start);
  /// One pass: due at `due`, begun at `began`, its work done at `ended`.
  void Record(Clock::time_point due, Clock::time_point began, Clock::time_point ended);
  /// Fills out's rate, jitter, step, steps and overruns with the passes since the previous
  /// call (or the start) until `now`, and starts the next period. Other fields are left alone.
  void Fill(msg::LoopStatistics& out, Clock::time_point now);

  std::uint64_t passes() const { return passes_; }
  std::uint64_t missed() const { return missed_; }

 private:
  Clock::duration period_;
  Clock::time_point since_;
  std::uint64_t passes_ = 0, missed_ = 0, passes_in_period_ = 0;
  common::LatencyHistogram jitter_, step_;
};

}  // namespace handshare::dds
