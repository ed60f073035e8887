#include "handshare/controls/operator_command.hpp"

namespace handshare::controls {

const char* ToString(OperatorAction action) noexcept {
  switch (action) {
    case OperatorAction::kGoToWorld: return "go_to_world";
    case OperatorAction::kRestartTour: return "restart_tour";
    case OperatorAction::kEndTurn: return "end_turn";
  }
  return "unknown";
}

}  // namespace handshare::controls
