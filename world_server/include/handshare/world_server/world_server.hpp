#pragma once
/// The world server: owns a session. Publishes the scene state and the message board
/// (transient-local, so late joiners get them), tracks members joining, leaving and
/// vanishing, and prints every change. One per session.
#include <chrono>
#include <string>

#include "handshare/common/node_main.hpp"

namespace handshare::world {

struct WorldServerConfig {
  common::SessionOptions where;  // domain, session, duration, QoS file
  std::string scene = "start_menu";
  double tick_Hz = 60.0;
};

class WorldServer {
 public:
  explicit WorldServer(WorldServerConfig config);
  /// Runs until --duration passes or a shutdown signal arrives. Returns the exit code.
  int Run();

 private:
  WorldServerConfig config_;
};

}  // namespace handshare::world
