#include "console_log.hpp"

#include <algorithm>
#include <cstdio>
#include <sstream>

namespace handshare::server {

namespace {

std::string Line(const LineSaid& e) { return e.line; }

std::string Line(const MemberChanged& e) {
  const Member& m = e.event.member;
  std::ostringstream line;
  line << "member " << ToString(e.event.change) << ": user=" << m.user << " kind=" << m.kind;
  if (!m.device.empty()) line << " device=" << m.device;
  line << " pid=" << m.pid << " present=" << e.present;
  if (!m.device_caps.empty()) line << " (device: " << m.device_caps << ")";
  return line.str();
}

std::string Line(const ControlApplied& e) {
  const ControlRecord& r = e.record;
  char line[200];
  std::snprintf(line, sizeof line, "control %s: %s by %s (value %.3f, error %s)", r.control_id.c_str(), LogName(r.kind),
                r.user.c_str(), r.value, r.error_m ? (std::to_string(1e3 * *r.error_m).substr(0, 5) + " mm").c_str() : "-");
  return line;
}

std::string Line(const SceneShown& e) { return "scene '" + e.scene + "': " + e.title; }

std::string Line(const OwnershipChanged& e) {
  const OwnershipChange& c = e.change;
  return "object '" + c.object_id + "': owner '" + c.previous_owner + "' -> '" + c.owner + "' (" + ToString(c.reason) +
         ")";
}

// The board's English text (every scene file has it; else its first language's).
std::string Line(const MessageSaid& e) {
  if (e.messages.empty()) return "";
  const auto en = std::find_if(e.messages.begin(), e.messages.end(), [](const auto& m) { return m.language == "en"; });
  return "message board #" + std::to_string(e.message_id) + ": " + (en != e.messages.end() ? en->text : e.messages[0].text);
}

std::string Line(const TurnEnded& e) {
  char line[300];
  if (e.ended_by.empty()) {
    std::snprintf(line, sizeof line, "visitor's turn ended: user=%s after %.3f s (--visit-minutes %g)",
                  e.member.user.c_str(), std::chrono::duration<double>(e.turn).count(), e.minutes);
  } else {
    std::snprintf(line, sizeof line, "visitor's turn ended: user=%s after %.3f s (by the operator, %s)",
                  e.member.user.c_str(), std::chrono::duration<double>(e.turn).count(), e.ended_by.c_str());
  }
  return line;
}

std::string Line(const VisitAnswered& e) {
  int answered = 0;
  for (const auto& kind : e.answers.scores) {
    for (auto score : kind) answered += score > 0 ? 1 : 0;
  }
  return "questionnaire: visitor=" + e.answers.visitor + " sent by " + e.sent_by + ", " + std::to_string(answered) +
         " answers";
}

template <typename Event>
std::string Line(const Event&) {
  return "";
}

}  // namespace

std::string ConsoleLine(const SessionEvent& event) {
  return std::visit([](const auto& e) { return Line(e); }, event);
}

ConsoleLog::ConsoleLog(std::function<void(const std::string&)> say) : say_(std::move(say)) {}

void ConsoleLog::Take(std::span<const SessionEvent> events, Clock::time_point /*now*/) {
  for (const SessionEvent& event : events) {
    if (std::string line = ConsoleLine(event); !line.empty()) say_(line);
  }
}

}  // namespace handshare::server
