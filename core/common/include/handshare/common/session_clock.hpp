#pragma once
/// The session's clock: the time every node of a session agrees on for what moves by itself
/// (periodic motions, the Daphnia swimming). The world server picks the session's origin once,
/// as Unix time (SceneState::session_epoch_unix_ns); each node turns it into a point of its
/// own steady clock when the scene state arrives, and from then on reads only the steady
/// clock. So the phase never jumps: not at midnight UTC (as seconds-of-the-day did), not when
/// the wall clock is stepped (NTP, an operator) during the session. Across hosts, the nodes
/// agree as well as their wall clocks did at the moment each converted the origin.
#include <cstdint>

#include "handshare/common/clock.hpp"

namespace handshare::common {

class SessionClock {
 public:
  /// A clock whose origin is now (the world server's own, before it publishes one).
  SessionClock() noexcept : steady_origin_ns_(static_cast<std::int64_t>(SteadyNowNs())) {}

  /// The clock of a session whose origin is epoch_unix_ns, converted with this host's clocks
  /// now (unix_now_ns, steady_now_ns: pass the current readings; tests pass their own).
  static SessionClock FromEpoch(std::uint64_t epoch_unix_ns, std::uint64_t unix_now_ns = UnixNowNs(),
                                std::uint64_t steady_now_ns = SteadyNowNs()) noexcept {
    SessionClock c;
    const auto since_origin_ns = static_cast<std::int64_t>(unix_now_ns - epoch_unix_ns);
    c.steady_origin_ns_ = static_cast<std::int64_t>(steady_now_ns) - since_origin_ns;
    return c;
  }

  /// Seconds since the session's origin at steady time steady_ns. Real-time safe.
  double At_s(std::uint64_t steady_ns) const noexcept {
    return 1e-9 * static_cast<double>(static_cast<std::int64_t>(steady_ns) - steady_origin_ns_);
  }
  /// Seconds since the session's origin, now. Real-time safe (reads the steady clock).
  double Now_s() const noexcept { return At_s(SteadyNowNs()); }

  /// The origin as Unix time by this host's clocks now (what the world server publishes).
  std::uint64_t EpochUnixNs(std::uint64_t unix_now_ns = UnixNowNs(),
                            std::uint64_t steady_now_ns = SteadyNowNs()) const noexcept {
    const auto since_origin_ns = static_cast<std::int64_t>(steady_now_ns) - steady_origin_ns_;
    return static_cast<std::uint64_t>(static_cast<std::int64_t>(unix_now_ns) - since_origin_ns);
  }

 private:
  std::int64_t steady_origin_ns_ = 0;  // the origin on this host's steady clock
};

}  // namespace handshare::common
