#include "handshare/common/overload_watch.hpp"

#include <algorithm>
#include <cstdio>
#include <utility>

namespace handshare::common {

OverloadWatch::OverloadWatch(std::string what, OverloadLimits limits) : what_(std::move(what)), limits_(limits) {}

std::string OverloadWatch::Tick(std::uint64_t now_ns, double asked_s) {
  if (window_start_ns_ == 0) {
    window_start_ns_ = last_ns_ = now_ns;
    return {};
  }
  const double period_s = 1.0 / limits_.rate_Hz;
  const double asked = asked_s > 0.0 ? asked_s : period_s;
  const double interval_s = now_ns > last_ns_ ? 1e-9 * static_cast<double>(now_ns - last_ns_) : 0.0;
  if (overloaded_) overloaded_s_ += interval_s;
  last_ns_ = now_ns;
  longest_s_ = std::max(longest_s_, interval_s);
  most_over_s_ = std::max(most_over_s_, interval_s - asked);
  asked_sum_s_ += asked;
  const double span_s = 1e-9 * static_cast<double>(now_ns - window_start_ns_);
  // A single interval past the bound says so at once; the rate only over a whole window.
  const bool late = most_over_s_ > limits_.max_interval_s - period_s;
  if (span_s < limits_.window_s && !(late && !overloaded_)) return {};
  // The ticks run, as a rate of the asked one's: ticks / span when every interval asked 1 / rate_Hz.
  const double rate_Hz = span_s > 0.0 ? limits_.rate_Hz * asked_sum_s_ / span_s : 0.0;
  const bool slow = span_s >= limits_.window_s && rate_Hz < limits_.min_rate_Hz;
  const double longest_ms = 1e3 * longest_s_;
  window_start_ns_ = now_ns;
  longest_s_ = 0.0;
  most_over_s_ = 0.0;
  asked_sum_s_ = 0.0;
  char line[320];
  if (!overloaded_ && (slow || late)) {
    overloaded_ = true;
    ++episodes_;
    since_ns_ = now_ns;
    std::snprintf(line, sizeof line,
                  "the machine is overloaded: %s ran at %.1f Hz of %.0f over the last %.1f s (longest interval "
                  "%.0f ms): what it carries arrives late",
                  what_.c_str(), rate_Hz, limits_.rate_Hz, span_s, longest_ms);
    return line;
  }
  if (overloaded_ && !slow && !late && span_s >= limits_.window_s) {
    overloaded_ = false;
    std::snprintf(line, sizeof line, "%s keeps its rate again (%.1f Hz of %.0f, longest interval %.0f ms) after %.1f s overloaded",
                  what_.c_str(), rate_Hz, limits_.rate_Hz, longest_ms, 1e-9 * static_cast<double>(now_ns - since_ns_));
    return line;
  }
  return {};
}

void OverloadWatch::Restart(std::uint64_t now_ns) {
  if (window_start_ns_ == 0) return;  // no tick yet: the first tick starts the window
  if (overloaded_ && now_ns > last_ns_) overloaded_s_ += 1e-9 * static_cast<double>(now_ns - last_ns_);
  window_start_ns_ = last_ns_ = now_ns;
  longest_s_ = 0.0;
  most_over_s_ = 0.0;
  asked_sum_s_ = 0.0;
}

std::string OverloadWatch::Summary() const {
  if (episodes_ == 0) return "no overload";
  char line[96];
  std::snprintf(line, sizeof line, "overloaded %d time(s), %.1f s in all", episodes_, overloaded_s_);
  return line;
}

}  // namespace handshare::common
