// world_server: owns a shared session (scene state, message board, members).
#include "handshare/node/node_main.hpp"
#include "handshare/world_server/world_server.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "world_server", "Owns a shared handshare session: publishes the scene and the message board, "
                      "tracks members joining and leaving, arbitrates grasped objects, publishes "
                      "deformations and rigid bodies' states, and records the session with --log.");
  handshare::node::DeclareSessionOptions(options);
  options.Value("scene", "NAME", "scene to start with (assets/scenes/NAME.json)", "start_menu")
      .Value("log", "FILE", "record the session in this SQLite session log (a new session is appended; "
                            "read it with session_report)", "")
      .Value("cache", "DIR", "deformable models' cache (default: $HANDSHARE_CACHE, else ~/.cache/handshare)", "")
      .Value("dump-deformation", "DIR", "write the loads and field of every published deformation to DIR "
                                        "(for an independent FEM check)", "")
      .Value("pose-trace", "FILE", "write every published rigid-body state to a CSV file (stamp_ns on the host's "
                                   "steady clock, object_id, owner, position, velocity)", "")
      .Value("deformation-threshold", "M", "re-send a deformed surface node when it moved more than M metres", "1e-4")
      .Value("resume-within", "SEC", "with --log: a session of this name whose server was killed less than SEC "
                                     "ago is resumed where it was (0: always start afresh)", "600");
  return handshare::node::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::server::WorldServerConfig config;
    config.where = handshare::node::ReadSessionOptions(o);
    config.scene = o.GetString("scene");
    config.log_file = o.GetString("log");
    config.cache_dir = o.GetString("cache");
    config.dump_dir = o.GetString("dump-deformation");
    config.pose_trace_file = o.GetString("pose-trace");
    config.deformation_threshold_m = o.GetDouble("deformation-threshold", 1e-9, 0.01);
    config.resume_within_s = o.GetDouble("resume-within", 0.0, 1e9);
    return handshare::server::WorldServer(config).Run();
  });
}
