#pragma once
/// What the operator's page shows, as plain data (no DDS types): filled by the console from the
/// session's topics, turned into the one JSON document every viewer receives (over the
/// WebSocket, and at GET /api/state). Not real-time.
#include <array>
#include <chrono>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "handshare/web_console/world_routes.hpp"

namespace handshare::web_console {

/// One station's loop, from its newest LoopStatistics sample.
struct StationStats {
  std::string node;      ///< the sample's key, e.g. "haptic_node/alice"
  std::string user;      ///< the user part of node ("alice")
  std::string device;    ///< from the user's member info ("sim", "hiro", ...); "" if unknown
  double rate_Hz = 0.0;
  double jitter_p50_us = 0.0;
  double jitter_p99_us = 0.0;
  double step_p99_us = 0.0;
  std::uint64_t steps = 0;
  std::uint64_t overruns = 0;
  std::uint64_t resyncs = 0;
  std::uint64_t faults = 0;
  std::uint64_t samples_dropped = 0;
  std::chrono::steady_clock::time_point received;
};

struct MemberRow {
  std::string user;
  std::string kind;    ///< "world_server", "haptic", "graphics", "audio_guide"
  std::string device;
};

/// One object of the current world as the 3-D view draws it (the scene state's object, with the
/// scene file's mesh scale).
struct ViewObject {
  std::string id;
  std::string kind;                 ///< "rigid", "deformable", "control"
  std::string shape;                ///< "box", "sphere", "mesh"
  std::string mesh;                 ///< URL of its .glb ("/meshes/NAME.glb"); "" unless a mesh
  std::array<double, 3> p_WO_m{};
  std::array<double, 4> q_WO_wxyz{1, 0, 0, 0};
  std::array<double, 3> half_extent_m{};
  std::array<double, 3> mesh_scale{1, 1, 1};
  std::array<float, 3> rgb{};
};

/// One user's hand for the view: the fingertips the device has, in W.
struct HandView {
  std::string user;
  std::vector<int> fingers;                    ///< finger index of each tip (thumb 0)
  std::vector<std::array<double, 3>> p_WE_m;   ///< fingertip centres
  double fingertip_radius_m = 0.0;
};

struct WorldView {
  bool known = false;   ///< a scene state has come
  std::string scene;
  std::string title;    ///< from the scene file, "" if the console cannot load it
  std::uint32_t revision = 0;
  double tick_Hz = 0.0;
  double gravity_z_m_per_s2 = 0.0;
  std::size_t objects = 0;
  std::vector<ViewObject> view;  ///< what the 3-D view draws
};

struct BoardView {
  std::uint32_t message_id = 0;
  std::string text;
  std::string next_action;
};

struct ConsoleState {
  std::string session;
  std::string console_name;
  bool actions_enabled = false;                  ///< a token is set (--token-file)
  WorldView world;
  std::vector<WorldRoute> routes;                ///< worlds the current one links to
  std::map<std::string, BoardView> boards;       ///< by language
  std::map<std::string, StationStats> stations;  ///< by node
  std::map<std::string, MemberRow> members;      ///< by member id
  std::uint64_t samples_refused = 0;             ///< samples the console's checks dropped
  std::uint64_t viewers = 0;                     ///< WebSocket viewers now
  std::uint64_t viewers_dropped = 0;             ///< viewers dropped for not keeping up
};

/// The state as the page reads it (docs/web_console.md, "The state document"). Text from the
/// session that is not valid UTF-8 is replaced, not refused. `now` ages the stations.
std::string ToJson(const ConsoleState& state, std::chrono::steady_clock::time_point now);

/// The hands document the view reads ({"type": "hands", "hands": [...]}), sent apart from the
/// state and more often.
std::string HandsJson(const std::map<std::string, HandView>& hands);  // any key: the order of the list

/// The user of a station's node key: what follows the last '/', else the whole key.
std::string UserOfNode(const std::string& node);

}  // namespace handshare::web_console
