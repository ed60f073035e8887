#pragma once
/// The consumer of the session's events that records them in the session log (SessionLog): the
/// only way from the tick into the SQLite file. Members, worlds shown, control events, where
/// controls settled, ownership, where the session is, and the bodies' poses (at most every
/// kPoseLogPeriod a body); a checkpoint commits what is queued. Stamps each row with the wall
/// clock when it takes it (a control event keeps the time it was taken from the reader).
/// Private to the server library. Not real-time.
#include <chrono>
#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include "handshare/world_server/session_events.hpp"
#include "handshare/world_server/session_log.hpp"

namespace handshare::server {

class SessionLogWriter : public SessionEventSink {
 public:
  /// Rows go to `log`; `unix_now` stamps them [ns since the Unix epoch].
  explicit SessionLogWriter(SessionLog& log, std::function<std::uint64_t()> unix_now = nullptr);

  void Take(std::span<const SessionEvent> events, Clock::time_point now) override;

  static constexpr std::chrono::milliseconds kPoseLogPeriod{100};

 private:
  void LogPlace(const ControlStateChanged& e);
  void LogPose(const BodyState& body, Clock::time_point now);
  /// Commits what is queued (waits for the disk). A failure is the log's error(), which the
  /// world server reports once; the session goes on without the log.
  void Commit();

  SessionLog& log_;
  std::function<std::uint64_t()> unix_now_;
  std::map<std::string, Clock::time_point> pose_logged_;  // body -> when its pose was last logged
};

}  // namespace handshare::server
