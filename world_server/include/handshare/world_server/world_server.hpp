#pragma once
/// The world server: owns a session. Publishes the scene state and the message board
/// (transient-local, so late joiners get them), tracks members joining, leaving and
/// vanishing, and prints every change. One per session.
#include <chrono>
#include <string>

namespace handshare::world {

struct WorldServerConfig {
  int domain_id = 0;
  std::string session;
  std::string scene = "start_menu";
  std::chrono::duration<double> duration{0.0};  // 0: until SIGINT/SIGTERM
  double tick_Hz = 60.0;
  std::string qos_file;  // empty: the default profiles
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
