#pragma once
/// How the operator sends the session to another world: the world server changes worlds only
/// when a control of the current world whose action goes there is actuated (a button pressed, a
/// book's page turned, a lever moved to a detent; world_server/src/control_actions.cpp). The
/// console actuates that control in its own name with one control event, as a hand would; so
/// the operator reaches the worlds the current world links to, and the session log records who
/// sent the session where.
#include <cstdint>
#include <string>
#include <vector>

#include "handshare/controls/controls.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::web_console {

/// A world the current one links to, and the control event that goes there.
struct WorldRoute {
  std::string world;
  std::string control_id;
  controls::EventKind kind = controls::EventKind::kPressed;
  std::int32_t index = -1;  ///< book page, lever detent; -1 for buttons and arrows
};

/// One route per world `scene` links to (not to itself), in the order of its controls; where
/// several controls go to one world, a button or arrow is preferred (one event, no page or
/// detent to name).
std::vector<WorldRoute> WorldRoutes(const scene::Scene& scene);

/// The route to `world`, or nullptr.
const WorldRoute* FindRoute(const std::vector<WorldRoute>& routes, const std::string& world) noexcept;

}  // namespace handshare::web_console
