#include "handshare/dds/roster_rejoin.hpp"

#include <cstdio>

#include "handshare/dds/sample_checks.hpp"

namespace handshare::dds {

RosterRejoin::RosterRejoin(std::chrono::duration<double> after, std::string session)
    : after_(after), session_(std::move(session)), watch_(after) {}

void RosterRejoin::Take(Reader<msg::SessionRoster>& reader) {
  msg::SessionRoster r;
  SampleMeta meta;
  while (reader && reader.TakeNext(r, meta)) {
    if (!meta.valid_data || !CheckSessionRoster(r, session_).empty()) continue;
    std::vector<std::string> ids;
    for (const auto& m : r.members()) ids.push_back(m.to_string());
    OnRoster(std::move(ids));
  }
}

std::string RosterRejoin::Due(const std::vector<std::string>& heard, Clock::time_point now) {
  if (rejoins_ >= kMaxRejoins) return "";
  const std::vector<std::string> unheard = watch_.Unheard(heard, now);
  if (unheard.empty()) return "";
  ++rejoins_;
  char tail[160];
  std::snprintf(tail, sizeof tail, ", not heard here %.1f s after joining: leaving and joining again with a new "
                "participant (rejoin %d)", after_.count(), rejoins_);
  return "the world server has " + unheard.front() + tail;
}

}  // namespace handshare::dds
