#pragma once
/// The session report: what a session log says about one session. Per control and per kind of
/// control, hits, misses and the mean and standard deviation of the errors (after the paper's
/// Table 4), time spent in each world, who was there, the visitors' turns, and the
/// questionnaire's count, mean and sd per kind of control and question (the paper's Fig. 16). The statistics are pure functions of rows; ReadReport reads them
/// from a log file (read-only) and throws SessionLogError for a missing or foreign file.
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "handshare/world_server/session_log.hpp"

namespace handshare::server {

/// Sample mean and standard deviation (handshare/controls/control_table.hpp: the web console's
/// live Table 4 counts by the same rule).
using controls::Summary;
using controls::Summarize;

struct ControlStats {
  std::string control_id;
  std::size_t hits = 0;       // pressed, moved, page_turned
  std::size_t misses = 0;     // missed
  std::size_t released = 0;
  /// error_m of the hits that carry one: how far from the target the hits landed. A miss's
  /// distance is a different quantity; it stays in the log, not in this summary.
  Summary error_m;
  /// Misses per user, over the users who tried this control (hit or miss): the paper's
  /// Table 4 (count = users, mean and sd of their misses).
  Summary misses_per_user;
};
/// One row per control id, sorted by id.
std::vector<ControlStats> ComputeControlStats(const std::vector<ControlRecord>& events);

/// The paper's Table 4 by kind of control (arrow, book, button, lever; "unknown" for controls of
/// a log that does not say their kind, before schema version 4): the events of every control
/// of a kind together, as ControlStats does for one control. Users: those who tried a control
/// of the kind; their misses are counted over all its controls.
struct KindStats {
  std::string kind;
  std::size_t controls = 0;   // control ids of this kind with events
  std::size_t hits = 0, misses = 0, released = 0;
  Summary error_m;
  Summary misses_per_user;
};
/// One row per kind with events, in the paper's order (alphabetical), "unknown" last.
std::vector<KindStats> ComputeKindStats(const std::vector<ControlRecord>& events,
                                        const std::map<std::string, scene::ControlType>& kinds);

/// One score of a visitor's questionnaire, as the log holds it.
struct AnswerRow {
  std::string visitor;
  scene::ControlType kind = scene::ControlType::kButton;
  controls::VisitQuestion question = controls::VisitQuestion::kEase;
  int score = 0;  // 1..7
};
/// The questionnaire's table (the paper's Fig. 16 and Table 3): count, mean and sd of the
/// scores of each question for each kind of control.
struct QuestionStats {
  scene::ControlType kind = scene::ControlType::kButton;
  controls::VisitQuestion question = controls::VisitQuestion::kEase;
  Summary score;
};
/// Every kind (paper's order: arrow, book, button, lever) times every question (ease,
/// naturalness, satisfaction), 12 rows, n = 0 where nobody answered.
std::vector<QuestionStats> ComputeQuestionnaire(const std::vector<AnswerRow>& answers);

struct SceneChange {
  std::uint64_t unix_ns = 0;
  std::string scene, title;
};
struct WorldTime {
  std::string scene, title;   // title of the last visit
  std::size_t visits = 0;
  double seconds = 0.0;
};
/// Time in each world: a world lasts from its scene change to the next one, the last to
/// end_unix_ns. Changes after end_unix_ns count nothing. Sorted by first visit.
std::vector<WorldTime> ComputeWorldTimes(std::vector<SceneChange> changes, std::uint64_t end_unix_ns);

struct MemberEventRow {
  std::uint64_t unix_ns = 0;
  MemberChange change = MemberChange::kJoined;
  Member member;
};
struct MemberStay {
  Member member;
  std::uint64_t joined_unix_ns = 0;
  std::optional<std::uint64_t> gone_unix_ns;  // empty: still present when the log ends
  std::string how;                             // "left", "lost", "present at end"
};
/// Pairs each join with the member's next leave or loss (a member may join again later).
std::vector<MemberStay> ComputeStays(std::vector<MemberEventRow> events);

struct SessionSummary {
  std::int64_t id = 0;
  std::string name, host;
  int domain_id = 0;
  std::int64_t pid = 0;
  std::uint64_t started_unix_ns = 0, last_seen_unix_ns = 0;
  std::optional<std::uint64_t> ended_unix_ns;  // empty: the server did not end it (killed)
  std::uint64_t dropped_rows = 0;
  std::uint64_t end_unix_ns() const { return ended_unix_ns.value_or(last_seen_unix_ns); }
};

/// One station's loop statistics over the session (schema version 5): its samples, and the
/// newest one's counts (they count from the node's start).
struct StationStats {
  std::string node;
  std::size_t samples = 0;
  std::uint64_t first_unix_ns = 0, last_unix_ns = 0;
  double rate_mean_Hz = 0.0, rate_min_Hz = 0.0;
  double jitter_p99_max_us = 0.0;     // the worst period's p99
  double sent_bytes_per_s_mean = 0.0;
  LoopRecord last;                    // the newest sample
};

struct SessionReport {
  std::filesystem::path file;
  std::size_t sessions_in_file = 0;
  SessionSummary session;
  std::vector<MemberStay> members;
  std::vector<WorldTime> worlds;
  std::vector<ControlStats> controls;
  std::size_t control_events = 0;
  std::size_t ownership_changes = 0;
  std::vector<KindStats> kinds;              // Table 4 by kind of control
  std::vector<TurnRecord> turns;             // visitors' turns that ended, by end
  std::vector<QuestionStats> questionnaire;  // 12 rows (ComputeQuestionnaire)
  std::size_t questionnaires = 0;            // visitors' questionnaires (distinct sends)
  std::vector<StationStats> stations;        // by node; none before schema version 5
};

/// Every session in the file, oldest first.
std::vector<SessionSummary> ListSessions(const std::filesystem::path& file);
/// The report of session `session_id`, or of the newest session. Throws SessionLogError
/// (missing file, not a log, unknown session, empty log).
SessionReport ReadReport(const std::filesystem::path& file, std::optional<std::int64_t> session_id = {});

/// Human-readable tables. The questionnaire, Table 4 by kind and the visitors' turns come
/// after every line older reports printed, which stay as they were; the stations after them.
void PrintReport(std::ostream& out, const SessionReport& report);
/// Long-format CSV, one value per line: session,section,item,field,value. Sections
/// control_kind, questionnaire and turn follow the older ones, then station.
void PrintReportCsv(std::ostream& out, const SessionReport& report);

}  // namespace handshare::server
