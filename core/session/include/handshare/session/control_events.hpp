#pragma once
/// Control events at the DDS boundary: the one place where the models' event kind
/// (controls::EventKind) and the message's (msg::ControlEventKind) are mapped onto each other.
/// Everything on either side uses controls::EventKind. Not real-time (the bridge thread and
/// the world server's tick).
#include <cstdint>
#include <optional>
#include <string>

#include "handshare/controls/controls.hpp"
#include "handshare/dds/messages.hpp"

namespace handshare::session {

msg::ControlEventKind ToMessage(controls::EventKind kind) noexcept;
/// The kind of a received event; empty for a value outside the IDL's enumeration (a bad sample).
std::optional<controls::EventKind> FromMessage(msg::ControlEventKind kind) noexcept;

/// The sample a haptic node sends for one of its controls' events.
msg::ControlEvent ToMessage(const controls::ControlEvent& event, const std::string& session,
                            const std::string& user, std::uint64_t stamp_ns);

}  // namespace handshare::session
