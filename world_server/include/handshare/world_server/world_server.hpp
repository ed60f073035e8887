#pragma once
/// The world server: owns a session. Each tick takes the samples that arrived, runs the
/// session's tick (a function from its state and those inputs to domain events,
/// session_events.hpp) and hands the events to its consumers: the DDS publisher (scene state
/// and message board transient-local, so late joiners get them), the session log when one is
/// configured (SessionLog), the pose trace, and the console, which prints every change.
/// One per session.
#include <chrono>
#include <fstream>
#include <memory>
#include <string>

#include "handshare/common/options.hpp"
#include "handshare/common/session_options.hpp"
#include "handshare/world_server/session_log.hpp"
#include "handshare/world_server/visit_turns.hpp"

namespace handshare::server {

struct WorldServerConfig {
  common::SessionOptions where;  // domain, session, duration, QoS file
  std::string scene = "start_menu";
  double tick_Hz = 60.0;
  std::string log_file;          // "": no session log; else SQLite file, a session is appended
  std::string cache_dir;         // deformable models' cache ("": world::DefaultCacheDir())
  std::string dump_dir;          // "": none; else every published deformation's loads (ObjectAuthority)
  std::string pose_trace_file;   // "": none; else a CSV row for every published rigid-body state
  double deformation_threshold_m = 1e-4;  // re-send a surface node when it moved more than this
  /// With a log file: a session of this name whose server was killed (never ended) at most this
  /// long ago is resumed where its log says it was; 0 never resumes.
  double resume_within_s = 600.0;
  /// A visitor's turn (a haptic member's, from its join) ends this many minutes later and the
  /// board says so; 0: turns never end.
  double visit_minutes = kDefaultVisitMinutes;
};

/// world_server's own options, beside node::DeclareSessionOptions'.
void DeclareWorldServerOptions(common::Options& options);
/// The configuration the parsed options give. Throws common::OptionError naming the option
/// and the range of a bad value.
WorldServerConfig ReadWorldServerOptions(const common::Options& options);

class WorldServer {
 public:
  explicit WorldServer(WorldServerConfig config);
  ~WorldServer();
  WorldServer(const WorldServer&) = delete;
  WorldServer& operator=(const WorldServer&) = delete;

  /// Loads the scene, opens the session log when one is configured (throws SessionLogError
  /// naming the file, before any DDS entity exists), and runs until --duration passes or a
  /// shutdown signal arrives. Returns the exit code: 0, or 1 when the session log failed during
  /// the run (the session itself went on).
  int Run();

  /// Prints one line of the server's log (stdout, with the time since start). The session's
  /// own lines come as events (ConsoleLog); these are the server's (the log, shutdown).
  void Say(const std::string& line);

 private:
  /// Reports a log failure once; true while the log is healthy.
  bool CheckLog();
  /// Ends the session in the log and commits what is queued.
  void CloseLog();

  WorldServerConfig config_;
  std::unique_ptr<SessionLog> log_;
  std::ofstream pose_trace_file_;
  bool log_failed_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace handshare::server
