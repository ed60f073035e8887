// world_server: owns a shared session (scene state, message board, members).
#include "handshare/common/node_main.hpp"
#include "handshare/world_server/world_server.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "world_server", "Owns a shared handshare session: publishes the scene and the message board, "
                      "tracks members joining and leaving.");
  options.Value("domain", "D", "DDS domain id (0..232)", "0")
      .Value("session", "S", "session name (DDS partition)", std::nullopt, true)
      .Value("scene", "NAME", "scene to start with (assets/scenes/NAME.json)", "start_menu")
      .Value("duration", "SEC", "run this long, then end (0: until SIGINT/SIGTERM)", "0")
      .Value("qos", "FILE", "QoS profile XML (default: deploy/qos/handshare_qos.xml)", "");
  return handshare::common::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::world::WorldServerConfig config;
    config.domain_id = static_cast<int>(o.GetInt("domain", 0, 232));
    config.session = o.GetString("session");
    config.scene = o.GetString("scene");
    config.duration = std::chrono::duration<double>(o.GetDouble("duration", 0.0, 1e7));
    config.qos_file = o.GetString("qos");
    return handshare::world::WorldServer(config).Run();
  });
}
