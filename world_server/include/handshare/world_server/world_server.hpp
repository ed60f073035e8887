#pragma once
/// The world server: owns a session. Publishes the scene state and the message board
/// (transient-local, so late joiners get them), tracks members joining, leaving and
/// vanishing, prints every change and, with a log file, records the session (SessionLog).
/// One per session.
#include <chrono>
#include <fstream>
#include <memory>
#include <string>

#include "handshare/common/session_options.hpp"
#include "handshare/world_server/member_registry.hpp"
#include "handshare/world_server/ownership_arbiter.hpp"
#include "handshare/world_server/session_log.hpp"

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
};

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

  /// Events of the session, printed and recorded in the log (once Run() opened it). Cheap: the
  /// log queues the row and a writer thread commits it. Call them from Run()'s thread (the
  /// log itself is thread-safe, the printing is not). The session's tick (ServerSession) calls
  /// them for every scene it publishes, control event, member change and ownership change.
  void OnControlEvent(const ControlRecord& event);
  void OnSceneChange(const std::string& scene, const std::string& title);
  void OnMemberEvent(const MemberEvent& event, std::size_t present);
  void OnOwnershipChange(const OwnershipChange& change);

  /// Prints one line of the server's log (stdout, with the time since start).
  void Say(const std::string& line);

  /// Commits what the log has queued now (waits for the disk: for the few rows a restart must
  /// find, control events and their effects). A failure is reported by the next CheckLog().
  void CommitLog();

  /// nullptr without a log file, or before Run() opened it.
  SessionLog* session_log() { return log_.get(); }
  /// nullptr without --pose-trace, or before Run() opened it. Rows: stamp_ns (the host's steady
  /// clock, as haptic_node's traces), object_id, owner, x, y, z [m], vx, vy, vz [m/s].
  std::ostream* pose_trace() { return pose_trace_.is_open() ? &pose_trace_ : nullptr; }

 private:
  /// Reports a log failure once; true while the log is healthy.
  bool CheckLog();
  /// Ends the session in the log and commits what is queued.
  void CloseLog();

  WorldServerConfig config_;
  std::unique_ptr<SessionLog> log_;
  std::ofstream pose_trace_;
  bool log_failed_ = false;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace handshare::server
