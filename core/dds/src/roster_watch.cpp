#include "handshare/dds/roster_watch.hpp"

#include <algorithm>

namespace handshare::dds {

std::vector<std::string> RosterWatch::Unheard(const std::vector<std::string>& heard, Clock::time_point now) {
  std::map<std::string, Clock::time_point> missing;
  std::vector<std::string> late;
  for (const std::string& id : roster_) {
    if (std::find(heard.begin(), heard.end(), id) != heard.end()) continue;
    const auto it = missing_since_.find(id);
    const Clock::time_point since = it != missing_since_.end() ? it->second : now;
    missing[id] = since;
    if (after_.count() > 0.0 && now - since >= after_) late.push_back(id);
  }
  missing_since_ = std::move(missing);  // heard or out of the roster: forgotten
  return late;
}

void RosterWatch::Restart(Clock::time_point now) {
  for (auto& [id, since] : missing_since_) since = now;
}

}  // namespace handshare::dds
