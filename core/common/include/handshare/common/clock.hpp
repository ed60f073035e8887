#pragma once
#include <chrono>
#include <cstdint>

namespace handshare::common {
/// Steady (monotonic) clock in ns: stamps for intervals and latency within one host.
inline std::uint64_t SteadyNowNs() noexcept {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::steady_clock::now().time_since_epoch()).count());
}
/// Wall clock in ns since the Unix epoch: stamps that mean something across hosts and logs.
inline std::uint64_t UnixNowNs() noexcept {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::system_clock::now().time_since_epoch()).count());
}
}  // namespace handshare::common
