#pragma once
/// An operator's command to the session: what the web console's operator may ask of it that no
/// control can (go to any world, restart the tour, end a visitor's turn). Plain data, as
/// controls::VisitAnswers; handshare/session/operator_command.hpp maps it to the message. Not
/// real-time.
#include <string>

namespace handshare::controls {

enum class OperatorAction {
  kGoToWorld,    ///< the session to `world`
  kRestartTour,  ///< the session to the world it started in; every present visitor's turn afresh
  kEndTurn,      ///< `visitor`'s turn ends now
};

/// "go_to_world", "restart_tour", "end_turn" (log lines, the console's documents).
const char* ToString(OperatorAction action) noexcept;

struct OperatorCommand {
  OperatorAction action = OperatorAction::kRestartTour;
  std::string world;    ///< kGoToWorld: the world's name
  std::string visitor;  ///< kEndTurn: whose turn (a haptic member's user)
};

}  // namespace handshare::controls
