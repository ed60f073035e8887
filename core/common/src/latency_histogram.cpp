#include "handshare/common/latency_histogram.hpp"

#include <algorithm>
#include <cmath>

namespace handshare::common {

namespace {
constexpr double kLogBase = 1.01;  // 1 % wide bins above the linear range
}

int LatencyHistogram::BinOf(double us) noexcept {
  if (!(us >= 0.0)) return 0;  // also catches NaN
  if (us < kLinearUs) return static_cast<int>(us);
  const int log_bin = static_cast<int>(std::log(us / kLinearUs) / std::log(kLogBase));
  return kLinearUs + std::min(log_bin, kLogBins - 1);
}

double LatencyHistogram::UpperEdge(int bin) noexcept {
  if (bin < kLinearUs) return bin + 1.0;
  return kLinearUs * std::pow(kLogBase, bin - kLinearUs + 1);
}

void LatencyHistogram::Record(double us) noexcept {
  ++bins_[static_cast<std::size_t>(BinOf(us))];
  ++count_;
  if (us > 0.0) sum_us_ += us;
  max_us_ = std::max(max_us_, us);
}

double LatencyHistogram::Quantile(double q) const noexcept {
  if (count_ == 0) return 0.0;
  const auto rank = static_cast<std::uint64_t>(std::ceil(std::clamp(q, 0.0, 1.0) * count_));
  std::uint64_t seen = 0;
  for (std::size_t b = 0; b < bins_.size(); ++b) {
    seen += bins_[b];
    if (seen >= std::max<std::uint64_t>(rank, 1)) {
      return std::min(UpperEdge(static_cast<int>(b)), max_us_);
    }
  }
  return max_us_;
}

}  // namespace handshare::common
