// world_server: owns a shared session (scene state, message board, members).
#include "handshare/node/node_main.hpp"
#include "handshare/world_server/world_server.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "world_server", "Owns a shared handshare session: publishes the scene and the message board, "
                      "tracks members joining and leaving, arbitrates grasped objects, publishes "
                      "deformations and rigid bodies' states, and records the session with --log.");
  handshare::node::DeclareSessionOptions(options);
  handshare::server::DeclareWorldServerOptions(options);
  return handshare::node::RunNodeMain(argc, argv, options, [](const auto& o) {
    return handshare::server::WorldServer(handshare::server::ReadWorldServerOptions(o)).Run();
  });
}
