// world_server: owns a shared session (scene state, message board, members).
#include "handshare/common/node_main.hpp"
#include "handshare/world_server/world_server.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "world_server", "Owns a shared handshare session: publishes the scene and the message board, "
                      "tracks members joining and leaving.");
  handshare::common::DeclareSessionOptions(options);
  options.Value("scene", "NAME", "scene to start with (assets/scenes/NAME.json)", "start_menu");
  return handshare::common::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::world::WorldServerConfig config;
    config.where = handshare::common::ReadSessionOptions(o);
    config.scene = o.GetString("scene");
    return handshare::world::WorldServer(config).Run();
  });
}
