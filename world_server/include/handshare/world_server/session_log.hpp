#pragma once
/// The session log: one SQLite file that records what happened in sessions (who joined, left or
/// was lost, which world was shown when, every control event with its error, ownership changes),
/// for the session report (session_report) and for studies like the paper's Table 4.
///
/// Writes never wait on the disk in the caller's thread: the On* calls queue a row (a mutex and a
/// push), and a writer thread commits the queued rows in one transaction every flush period
/// (WAL journal, synchronous=NORMAL). Re-opening an existing log appends a new session to it.
/// Times are wall-clock ns since the Unix epoch (common::UnixNowNs()), comparable across hosts.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "handshare/contact/finger_contact.hpp"  // contact::Vec3, QuatWxyz
#include "handshare/controls/controls.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/controls/control_table.hpp"
#include "handshare/controls/visit_answers.hpp"
#include "handshare/world_server/member_registry.hpp"

namespace handshare::server {

/// A log file that cannot be opened, created, read or written; what() names the file and
/// what failed ("file is not a database", "unable to open database file", ...).
class SessionLogError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Control events are logged with the one kind every layer uses (controls::EventKind, mapped
/// from the IDL's ControlEventKind once, at the DDS boundary: handshare/session/control_events.hpp),
/// by their log names: "pressed", "released", "moved", "page_turned", "missed", "opened".
/// A hit is kPressed, kMoved, kPageTurned or kOpened (one event per hit: a lever reports one
/// kMoved per push, a book one kOpened when its cover opens); kReleased is neither a hit nor a
/// miss; kMissed is a try that did not hit the control.
const char* LogName(controls::EventKind kind);
std::optional<controls::EventKind> EventKindFromLogName(std::string_view text);
using controls::IsHit;  // the rule both Table 4s count by (handshare/controls/control_table.hpp)

struct ControlRecord {
  std::uint64_t unix_ns = 0;
  std::string user;
  std::string control_id;
  controls::EventKind kind = controls::EventKind::kPressed;
  double value = 0.0;                 // lever angle [rad], page number, ...
  std::optional<double> error_m;      // distance of the touch from the control's target [m]
};

/// A visitor's turn that ended (world_server --visit-minutes): from the member's join.
struct TurnRecord {
  std::uint64_t started_unix_ns = 0;
  std::uint64_t ended_unix_ns = 0;
  std::string member_id;
  std::string user;
};

/// A station's loop statistics (a LoopStatistics sample, checked) as the world server took it.
struct LoopRecord {
  std::uint64_t unix_ns = 0;
  std::string node;                       // haptic_node/USER, graphics_node/NAME, audio_guide/NAME
  double rate_Hz = 0.0;
  double jitter_p50_us = 0.0, jitter_p99_us = 0.0, jitter_max_us = 0.0;
  double step_p50_us = 0.0, step_p99_us = 0.0;
  std::uint64_t steps = 0, overruns = 0, resyncs = 0, faults = 0, samples_dropped = 0, deadline_misses = 0;
  double sent_bytes_per_s = 0.0;
};
/// Who and where a session is: written once when the log opens.
struct SessionStart {
  std::string name;                   // the DDS session (partition)
  int domain_id = 0;
  std::string host;
  std::int64_t pid = 0;
  std::uint64_t unix_ns = 0;
  std::int64_t resumed_from = 0;      // the session this one resumes (0: a new session)
};

/// Where a session is: what a restarted server needs to go on from there.
struct SessionState {
  std::uint64_t unix_ns = 0;
  std::string scene;                      // the current world
  std::string title;
  std::uint32_t revision = 0;             // of the scene state last published
  contact::Vec3 gravity_W_m_per_s2{};
  std::uint64_t epoch_unix_ns = 0;        // the session clock's origin
  std::uint32_t message_id = 0;           // the board's last message ...
  std::vector<scene::Message> board;      // ... in every language
};

/// The newest pose of a rigid body and who held it.
struct ObjectPose {
  std::string object_id;
  std::string owner;                      // "" free
  std::uint64_t unix_ns = 0;
  contact::Vec3 p_WO_m{};
  contact::QuatWxyz q_WO_wxyz{1.0, 0.0, 0.0, 0.0};
};

/// Where a control of the current world settled (its events; a hand's motion is not kept).
struct ControlPlace {
  std::string control_id;
  std::string scene;                      // the world it belongs to
  std::uint64_t unix_ns = 0;
  std::int32_t index = -1;                // lever: detent; book: page (-1 shut); else -1
  bool engaged = false;                   // button, arrow: pressed; book: open
  std::string user;                       // who changed it last ("" nobody yet)
  std::uint32_t changes = 0;              // events that changed it
};

/// A session a killed server left behind (never ended), with the state it last committed.
struct ResumePoint {
  std::int64_t session_id = 0;
  std::uint64_t last_seen_unix_ns = 0;    // the killed server's last commit
  SessionState state;
  std::vector<ObjectPose> poses;
  std::vector<ControlPlace> controls;     // none from a session logged before schema version 3
};

/// The newest session named `session` in `file` that did not end (its server was killed or
/// lost power), whose last commit is at most `max_age_ns` before `now_unix_ns`, and that
/// recorded a state. Empty when there is none (no file, a clean end, too old, no state).
/// Throws SessionLogError for a file that is not a readable session log.
std::optional<ResumePoint> FindResumePoint(const std::filesystem::path& file, const std::string& session,
                                           std::uint64_t now_unix_ns, std::uint64_t max_age_ns);

struct SessionLogConfig {
  std::chrono::milliseconds flush_period{200};  // the writer commits at least this often
  std::chrono::milliseconds busy_timeout{2000}; // waits this long for a reader's lock
  std::size_t max_queued_rows = 100000;         // beyond this, rows are dropped and counted
};

class SessionLog {
 public:
  /// Schema version (PRAGMA user_version); the file also carries kApplicationId.
  static constexpr int kSchemaVersion = 5;
  static constexpr std::int32_t kApplicationId = 0x48534C47;  // "HSLG"

  /// Opens `file` (created with the schema if absent or empty), checks it is a handshare log
  /// of a known schema version, switches it to WAL and inserts a new session row.
  /// Throws SessionLogError naming the file and the step that failed.
  SessionLog(const std::filesystem::path& file, const SessionStart& start,
             SessionLogConfig config = {});
  /// Ends the session (End(now) unless already ended) and commits what is queued.
  /// Never throws: an error at this point is kept in error().
  ~SessionLog();
  SessionLog(const SessionLog&) = delete;
  SessionLog& operator=(const SessionLog&) = delete;

  /// Queue a row; thread-safe, never blocks on the disk. After a write error they do nothing
  /// (the error is kept in error() and thrown by Flush()).
  void OnMember(MemberChange change, const Member& member, std::uint64_t unix_ns);
  void OnSceneChange(const std::string& scene, const std::string& title, std::uint64_t unix_ns);
  /// A hand's motion reports (kMoving) are not events of the session: not logged.
  void OnControlEvent(const ControlRecord& event);
  /// owner "" : the object became free.
  void OnOwnership(const std::string& object_id, const std::string& owner, const std::string& reason,
                   std::uint64_t unix_ns);
  /// Where the session is now (replaces the previous state: one row per session).
  void OnState(const SessionState& state);
  /// The newest pose of a body (replaces its previous pose).
  void OnObjectPose(const ObjectPose& pose);
  /// Another world: the poses of the last one are forgotten.
  void ForgetObjectPoses();
  /// Where a control settled (replaces its previous place).
  void OnControlPlace(const ControlPlace& place);
  /// Another world: the places of the last one's controls are forgotten.
  void ForgetControlPlaces();
  /// A visitor's turn ended.
  void OnTurnEnded(const TurnRecord& turn);
  /// A visitor's questionnaire (sent by the console `sent_by`): a row per answered score.
  void OnVisitAnswers(const std::string& sent_by, const controls::VisitAnswers& answers, std::uint64_t unix_ns);
  /// The kinds of the controls of a world the session shows (replaces a control's earlier kind).
  void OnControlKinds(const scene::Scene& scene);
  /// A station's loop statistics (every sample: about one a second per node).
  void OnLoopStatistics(const LoopRecord& loop);
  /// Marks the session as ended at unix_ns (once; later calls are ignored).
  void End(std::uint64_t unix_ns);

  /// Waits until everything queued so far is committed; throws SessionLogError if a write
  /// failed. Not for the world tick: for tests and shutdown.
  void Flush();

  std::int64_t session_id() const { return session_id_; }
  const std::filesystem::path& file() const { return file_; }
  /// The first write error, "" while healthy.
  std::string error() const;
  /// Rows dropped because the queue was full (the disk could not keep up).
  std::uint64_t dropped_rows() const;

 private:
  struct Impl;
  std::filesystem::path file_;
  std::int64_t session_id_ = 0;
  std::unique_ptr<Impl> impl_;
};

}  // namespace handshare::server
