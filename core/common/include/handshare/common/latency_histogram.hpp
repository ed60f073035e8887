#pragma once
/// Fixed-size histogram of durations in microseconds for p50/p99/max without allocation.
/// Resolution 1 us up to kLinearUs, then 1% wide logarithmic bins up to about 10 s.
/// Record() is real-time safe (no allocation, no lock); read it from the same thread or
/// copy it out first (it is trivially copyable).
#include <array>
#include <cstdint>

namespace handshare::common {

class LatencyHistogram {
 public:
  static constexpr int kLinearUs = 1000;
  static constexpr int kLogBins = 1000;

  void Record(double us) noexcept;
  void Reset() noexcept { *this = LatencyHistogram{}; }

  std::uint64_t count() const noexcept { return count_; }
  double max_us() const noexcept { return max_us_; }
  double mean_us() const noexcept { return count_ ? sum_us_ / static_cast<double>(count_) : 0.0; }
  /// q in [0, 1]; the upper edge of the bin holding the q-quantile (0 when empty).
  double Quantile(double q) const noexcept;

 private:
  static int BinOf(double us) noexcept;
  static double UpperEdge(int bin) noexcept;

  std::array<std::uint32_t, kLinearUs + kLogBins> bins_{};
  std::uint64_t count_ = 0;
  double sum_us_ = 0.0;
  double max_us_ = 0.0;
};

}  // namespace handshare::common
