#pragma once
/// An operator's command at the DDS boundary: the one place where controls::OperatorCommand and
/// msg::OperatorCommand are mapped onto each other (the web console sends, the world server
/// takes). Not real-time.
#include <cstdint>
#include <optional>
#include <string>

#include "handshare/controls/operator_command.hpp"
#include "handshare/dds/messages.hpp"

namespace handshare::session {

/// The sample the web console sends in its own name (`user`).
msg::OperatorCommand ToMessage(const controls::OperatorCommand& command, const std::string& session,
                               const std::string& user, std::uint64_t stamp_ns);
/// The command of a sample that dds::CheckOperatorCommand accepted (nullopt for a kind it
/// does not know, which the check refuses).
std::optional<controls::OperatorCommand> FromMessage(const msg::OperatorCommand& sample);

}  // namespace handshare::session
