#pragma once
/// What the operator's page shows, as plain data (no DDS types): filled by the console from the
/// session's topics, turned into the one JSON document every viewer receives (over the
/// WebSocket, and at GET /api/state). Not real-time.
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

struct WorldView {
  bool known = false;   ///< a scene state has come
  std::string scene;
  std::string title;    ///< from the scene file, "" if the console cannot load it
  std::uint32_t revision = 0;
  double tick_Hz = 0.0;
  double gravity_z_m_per_s2 = 0.0;
  std::size_t objects = 0;
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

/// The user of a station's node key: what follows the last '/', else the whole key.
std::string UserOfNode(const std::string& node);

}  // namespace handshare::web_console
