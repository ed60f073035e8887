#include "handshare/common/periodic_loop.hpp"

#include <thread>

namespace handshare::common {

PeriodicLoop::PeriodicLoop(std::chrono::nanoseconds period, int resync_after) noexcept
    : period_(period), resync_after_(resync_after), start_(Clock::now()), next_(start_),
      woke_(start_) {}

PeriodicLoop::Clock::time_point PeriodicLoop::WaitNext() noexcept {
  next_ += period_;
  const auto now = Clock::now();
  if (now > next_ + resync_after_ * period_) {
    // Far behind (stall, debugger, overloaded machine): restart the schedule rather than
    // running a burst of steps back to back.
    next_ = now;
    ++stats_.resyncs;
  } else {
    std::this_thread::sleep_until(next_);
  }
  woke_ = Clock::now();
  stats_.jitter.Record(std::chrono::duration<double, std::micro>(woke_ - next_).count());
  return woke_;
}

void PeriodicLoop::EndStep() noexcept {
  const auto end = Clock::now();
  stats_.step.Record(std::chrono::duration<double, std::micro>(end - woke_).count());
  ++stats_.steps;
  if (end > next_ + period_) ++stats_.overruns;
  const double elapsed_s = std::chrono::duration<double>(end - start_).count();
  stats_.rate_Hz = elapsed_s > 0.0 ? static_cast<double>(stats_.steps) / elapsed_s : 0.0;
}

}  // namespace handshare::common
