#include "handshare/dds/pass_statistics.hpp"

#include <algorithm>

namespace handshare::dds {

namespace {
double Us(PassStatistics::Clock::duration d) { return std::chrono::duration<double, std::micro>(d).count(); }
}  // namespace

PassStatistics::PassStatistics(Clock::duration period, Clock::time_point start) : period_(period), since_(start) {}

void PassStatistics::Record(Clock::time_point due, Clock::time_point began, Clock::time_point ended) {
  const Clock::duration late = std::max(began - due, Clock::duration::zero());
  jitter_.Record(Us(late));
  step_.Record(Us(std::max(ended - began, Clock::duration::zero())));
  ++passes_;
  ++passes_in_period_;
  if (late >= period_) ++missed_;
}

void PassStatistics::Fill(msg::LoopStatistics& out, Clock::time_point now) {
  const double period_s = std::chrono::duration<double>(now - since_).count();
  out.rate_Hz(period_s > 0.0 ? static_cast<double>(passes_in_period_) / period_s : 0.0);
  out.jitter_p50_us(jitter_.Quantile(0.5));
  out.jitter_p99_us(jitter_.Quantile(0.99));
  out.jitter_max_us(jitter_.max_us());
  out.step_p50_us(step_.Quantile(0.5));
  out.step_p99_us(step_.Quantile(0.99));
  out.steps(passes_);
  out.overruns(missed_);
  jitter_.Reset();
  step_.Reset();
  passes_in_period_ = 0;
  since_ = now;
}

}  // namespace handshare::dds
