#pragma once
/// The consumer of the session's events that prints what the operator reads: one line per
/// event that says something (members, control events, worlds shown, ownership, the board, and
/// every LineSaid), in the tick's order. The lines are the ones tests and operators wait for;
/// ConsoleLine() is the one place their wording lives. Private to the server library.
#include <functional>
#include <string>

#include "handshare/world_server/session_events.hpp"

namespace handshare::server {

/// The line `event` prints, "" for events that print nothing (samples, log rows).
std::string ConsoleLine(const SessionEvent& event);

class ConsoleLog : public SessionEventSink {
 public:
  /// Lines go to `say` (the world server's, which stamps them with the time since start).
  explicit ConsoleLog(std::function<void(const std::string&)> say);

  void Take(std::span<const SessionEvent> events, Clock::time_point now) override;

 private:
  std::function<void(const std::string&)> say_;
};

}  // namespace handshare::server
