#pragma once
/// The consumer of the session's events that writes the pose trace (--pose-trace): a CSV row
/// for every rigid-body state the session publishes. Rows: stamp_ns (the host's steady clock,
/// as haptic_node's traces; one stamp per tick), object_id, owner, x, y, z [m], vx, vy, vz
/// [m/s]. Flushed every tick that has rows: a test follows the file while the server runs.
/// Private to the server library.
#include <cstdint>
#include <functional>
#include <ostream>

#include "handshare/world_server/session_events.hpp"

namespace handshare::server {

class PoseTrace : public SessionEventSink {
 public:
  /// Writes the header row to `out`; `steady_now` stamps the rows [ns].
  explicit PoseTrace(std::ostream& out, std::function<std::uint64_t()> steady_now = nullptr);

  void Take(std::span<const SessionEvent> events, Clock::time_point now) override;

 private:
  std::ostream& out_;
  std::function<std::uint64_t()> steady_now_;
};

}  // namespace handshare::server
