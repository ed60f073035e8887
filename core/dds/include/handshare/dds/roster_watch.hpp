#pragma once
/// Which members of the world server's roster a node has not heard itself, and since when.
#include <chrono>
#include <map>
#include <string>
#include <vector>

namespace handshare::dds {

/// The members the world server has (its SessionRoster) that a node has not heard itself, and
/// since when. A node that hears the server but never one member has a DDS-Security handshake
/// with that member's participant that never finished (Fast DDS 2.9, docs/security.md); only a
/// new participant starts it again. Pure bookkeeping, no DDS.
class RosterWatch {
 public:
  using Clock = std::chrono::steady_clock;
  /// after: how long a member of the roster may go unheard; 0 or less: never report.
  explicit RosterWatch(std::chrono::duration<double> after) : after_(after) {}

  /// The roster as last received (member ids); replaces the previous one.
  void OnRoster(std::vector<std::string> member_ids) { roster_ = std::move(member_ids); }
  /// Of the roster, the members not in `heard` (the member ids this node has present) for at
  /// least `after` at `now`: since they appeared in the roster, or since the last Restart.
  std::vector<std::string> Unheard(const std::vector<std::string>& heard, Clock::time_point now);
  /// A new participant: every member's wait starts again at `now`.
  void Restart(Clock::time_point now);

 private:
  std::chrono::duration<double> after_;
  std::vector<std::string> roster_;
  std::map<std::string, Clock::time_point> missing_since_;
};

}  // namespace handshare::dds
