#pragma once
/// When a node should leave the session and join it again because the world server's roster
/// names a member it never hears: DDS-Security's handshake with that member's participant never
/// finished (Fast DDS 2.9, docs/security.md), and only a new participant starts it again. One
/// rule for every node that watches the roster (the spectator, the recorder).
#include <chrono>
#include <string>
#include <vector>

#include "handshare/dds/messages.hpp"
#include "handshare/dds/participant.hpp"
#include "handshare/dds/roster_watch.hpp"

namespace handshare::dds {

class RosterRejoin {
 public:
  using Clock = RosterWatch::Clock;
  /// At most this many rejoins: a member this node can never reach (another network, another
  /// fault) must not make it leave and join every `after` for ever.
  static constexpr int kMaxRejoins = 5;

  /// after: how long a member of the roster may stay unheard (0 or less: never rejoin).
  /// session: roster samples of other sessions, or malformed ones, are skipped.
  RosterRejoin(std::chrono::duration<double> after, std::string session);

  /// Takes every roster sample `reader` holds (an empty reader: a keystore without the grant).
  void Take(Reader<msg::SessionRoster>& reader);
  /// A roster's member ids, as Take passes them on.
  void OnRoster(std::vector<std::string> member_ids) { watch_.OnRoster(std::move(member_ids)); }
  /// `heard`: the member ids this node has present. When a member of the roster has not been
  /// among them for `after` and rejoins are left, counts one and returns the line to print
  /// ("the world server has M, not heard here N s after joining: leaving and joining again with
  /// a new participant (rejoin K)"); else "".
  std::string Due(const std::vector<std::string>& heard, Clock::time_point now);
  /// A new participant (this rule's rejoin or another's): every wait starts again at `now`.
  void Restart(Clock::time_point now) { watch_.Restart(now); }
  int rejoins() const { return rejoins_; }

 private:
  std::chrono::duration<double> after_;
  std::string session_;
  RosterWatch watch_;
  int rejoins_ = 0;
};

}  // namespace handshare::dds
