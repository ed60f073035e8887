#pragma once
/// A visitor's turn (the paper's section 1.7: "a maximum 10 minutes was set for those trying
/// out the FHSE", then a questionnaire): a haptic member's turn lasts from its join for
/// world_server --visit-minutes, then the board says it is over, in every language the board
/// has, and the session log records its end. No DDS, no clock: ServerSession keeps the turns.
#include <chrono>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "handshare/scene/scene.hpp"
#include "handshare/world_server/member_registry.hpp"

namespace handshare::server {

/// The paper's 10 minutes (world_server --visit-minutes' default).
inline constexpr double kDefaultVisitMinutes = 10.0;

/// The board's message when `user`'s turn of `minutes` is over: English and Japanese (with its
/// kana reading for the ja voice), under one number as every board message. Without `minutes`
/// (the operator ended the turn) it says the turn is over without a length.
std::vector<scene::Message> TurnOverMessages(const std::string& user, std::optional<double> minutes);

/// The turns of the members present: a haptic member's turn starts when it joins and ends once,
/// `length` later (0: turns never end by themselves), or when the operator ends it. A member
/// that leaves or is lost takes its turn along.
class VisitTurns {
 public:
  using Clock = std::chrono::steady_clock;
  explicit VisitTurns(Clock::duration length) : length_(length) {}

  /// A member joined (a visitor when its kind is haptic), left or was lost, at `now`.
  void OnMember(MemberChange change, const Member& member, Clock::time_point now);
  struct Ended {
    Member member;
    Clock::duration turn{};  ///< how long it lasted (at least `length`)
  };
  /// The turns that are over at `now`, each once, in the order they began.
  std::vector<Ended> TakeEnded(Clock::time_point now);
  /// `user`'s open turn, ended now (the operator's "end a visitor's turn"); nullopt when the
  /// user has none (not a present visitor, or its turn already ended).
  std::optional<Ended> EndNow(const std::string& user, Clock::time_point now);
  /// Every open turn ended now, and the turn of every visitor (haptic member) of `present`
  /// begun again at `now` (the operator's "restart the tour"): a visitor whose turn had ended
  /// gets a new one too.
  std::vector<Ended> Restart(const std::vector<Member>& present, Clock::time_point now);
  bool enabled() const { return length_ > Clock::duration::zero(); }

 private:
  struct Turn {
    Member member;
    Clock::time_point start;
  };
  Clock::duration length_;
  std::map<std::string, Turn> open_;  // by member_id
};

}  // namespace handshare::server
