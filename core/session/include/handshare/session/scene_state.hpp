#pragma once
/// The scene state every node builds its world from, made from a loaded scene: the world
/// server publishes it, and the graphics bench draws what a spectator draws from it without a
/// server. Pure: no participant, no clock read.
#include <cstdint>
#include <string>

#include "handshare/dds/messages.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::session {

/// Revision `revision` of `scene` (objects and the controls' visuals), with the session clock's
/// origin and the server's tick rate (how often it reads contact sets).
msg::SceneState ToSceneState(const scene::Scene& s, const std::string& session, std::uint32_t revision,
                             std::uint64_t session_epoch_unix_ns, double tick_Hz = 0.0);

}  // namespace handshare::session
