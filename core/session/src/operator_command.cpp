#include "handshare/session/operator_command.hpp"

namespace handshare::session {

msg::OperatorCommand ToMessage(const controls::OperatorCommand& command, const std::string& session,
                               const std::string& user, std::uint64_t stamp_ns) {
  using controls::OperatorAction;
  msg::OperatorCommand m;
  m.session(session);
  m.user(user);
  switch (command.action) {
    case OperatorAction::kGoToWorld: m.kind(msg::OPERATOR_GO_TO_WORLD); break;
    case OperatorAction::kRestartTour: m.kind(msg::OPERATOR_RESTART_TOUR); break;
    case OperatorAction::kEndTurn: m.kind(msg::OPERATOR_END_TURN); break;
  }
  if (command.action == OperatorAction::kGoToWorld) m.world(command.world);
  if (command.action == OperatorAction::kEndTurn) m.visitor(command.visitor);
  m.stamp_ns(stamp_ns);
  return m;
}

std::optional<controls::OperatorCommand> FromMessage(const msg::OperatorCommand& sample) {
  using controls::OperatorAction;
  controls::OperatorCommand c;
  switch (sample.kind()) {
    case msg::OPERATOR_GO_TO_WORLD:
      c.action = OperatorAction::kGoToWorld;
      c.world = sample.world().to_string();
      return c;
    case msg::OPERATOR_RESTART_TOUR: c.action = OperatorAction::kRestartTour; return c;
    case msg::OPERATOR_END_TURN:
      c.action = OperatorAction::kEndTurn;
      c.visitor = sample.visitor().to_string();
      return c;
  }
  return std::nullopt;
}

}  // namespace handshare::session
