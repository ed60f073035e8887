#pragma once
/// The world server's conversions between DDS samples and its own types: pure functions (no
/// participant, no clock read, no I/O), unit-tested without DDS
/// (world_server/test/server_conversions_test.cpp). Private to the server library.
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "handshare/dds/messages.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/session/scene_state.hpp"
#include "handshare/world_server/body_state.hpp"
#include "handshare/world_server/control_actions.hpp"
#include "handshare/world_server/deformation_delta.hpp"
#include "handshare/world_server/member_registry.hpp"
#include "handshare/world_server/session_log.hpp"

namespace handshare::server {

/// The scene state every node builds its world from (shared with the graphics bench).
using session::ToSceneState;

/// A member as announced.
Member ToMember(const msg::MemberInfo& info);

/// A received control event for the scene's logic; empty for a kind outside the IDL's
/// enumeration (a bad sample: dropped).
std::optional<ControlInput> ToControlInput(const msg::ControlEvent& e);

/// The session log's row of a control event received at unix_ns (a non-finite error is none).
ControlRecord ToControlRecord(const msg::ControlEvent& e, const ControlInput& input, std::uint64_t unix_ns);
/// A station's loop statistics for the log, taken at unix_ns.
LoopRecord ToLoopRecord(const msg::LoopStatistics& s, std::uint64_t unix_ns);

/// A control's state as published on handshare/control_state.
msg::ControlState ToControlState(const ControlStateRecord& r, const std::string& session);

/// The board sample of message number message_id.
msg::MessageBoard ToMessageBoard(const scene::Message& m, const std::string& session, std::uint32_t message_id);

/// A rigid body's state sample, stamped stamp_ns (the host's steady clock, when it is written).
msg::ObjectState ToObjectState(const BodyState& body, const std::string& session, std::uint64_t stamp_ns);

/// The members present, at most the IDL's bound of them (a session has far fewer).
msg::SessionRoster ToSessionRoster(const std::vector<std::string>& member_ids, const std::string& session);
inline constexpr std::size_t kMaxRoster = 64;  // the IDL's bound

/// One deformation sample of object_id.
msg::Deformation ToDeformation(const std::string& object_id, const std::string& session,
                               const DeformationSample& sample);

}  // namespace handshare::server
