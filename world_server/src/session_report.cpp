#include "handshare/world_server/session_report.hpp"

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <ctime>
#include <map>
#include <ostream>
#include <set>
#include <system_error>

#include "sqlite_db.hpp"

namespace handshare::server {

namespace {

/// Copies a tally's counts and its two summaries into a row (ControlStats or KindStats).
template <class Row>
void Fill(const controls::EventTally& tally, Row& row) {
  row.hits = tally.hits();
  row.misses = tally.misses();
  row.released = tally.released();
  row.error_m = tally.error_m();
  row.misses_per_user = tally.misses_per_user();
}

}  // namespace

std::vector<ControlStats> ComputeControlStats(const std::vector<ControlRecord>& events) {
  std::map<std::string, controls::EventTally> by_control;
  for (const auto& e : events) by_control[e.control_id].Add(e.kind, e.user, e.error_m);
  std::vector<ControlStats> out;
  for (const auto& [id, tally] : by_control) {
    ControlStats row;
    row.control_id = id;
    Fill(tally, row);
    out.push_back(row);
  }
  return out;
}

std::vector<KindStats> ComputeKindStats(const std::vector<ControlRecord>& events,
                                        const std::map<std::string, scene::ControlType>& kinds) {
  controls::KindTable table;
  for (const auto& e : events) {
    const auto k = kinds.find(e.control_id);
    table.Add(e.control_id, k == kinds.end() ? std::nullopt : std::optional<scene::ControlType>(k->second), e.kind, e.user,
              e.error_m);
  }
  std::vector<KindStats> out;
  for (const auto& r : table.Rows()) {
    KindStats row;
    row.kind = r.kind;
    row.controls = r.controls;
    Fill(r.tally, row);
    out.push_back(row);
  }
  return out;
}

std::vector<QuestionStats> ComputeQuestionnaire(const std::vector<AnswerRow>& answers) {
  using scene::ControlType;
  using controls::VisitQuestion;
  std::vector<QuestionStats> out;
  for (ControlType kind : {ControlType::kArrow, ControlType::kBook, ControlType::kButton, ControlType::kLever}) {
    for (VisitQuestion q : {VisitQuestion::kEase, VisitQuestion::kNaturalness, VisitQuestion::kSatisfaction}) {
      std::vector<double> scores;
      for (const auto& a : answers) {
        if (a.kind == kind && a.question == q) scores.push_back(static_cast<double>(a.score));
      }
      out.push_back(QuestionStats{kind, q, Summarize(scores)});
    }
  }
  return out;
}

std::vector<WorldTime> ComputeWorldTimes(std::vector<SceneChange> changes, std::uint64_t end_unix_ns) {
  std::stable_sort(changes.begin(), changes.end(),
                   [](const SceneChange& a, const SceneChange& b) { return a.unix_ns < b.unix_ns; });
  std::vector<WorldTime> out;
  const std::string* previous = nullptr;
  for (std::size_t i = 0; i < changes.size(); ++i) {
    const SceneChange& c = changes[i];
    if (c.unix_ns >= end_unix_ns) break;
    const std::uint64_t stop = i + 1 < changes.size() ? std::min(changes[i + 1].unix_ns, end_unix_ns) : end_unix_ns;
    auto it = std::find_if(out.begin(), out.end(), [&](const WorldTime& w) { return w.scene == c.scene; });
    if (it == out.end()) it = out.insert(out.end(), WorldTime{c.scene, c.title, 0, 0.0});
    it->title = c.title;
    // Publishing the same world again (a reload) is not a new visit.
    if (!previous || *previous != c.scene) ++it->visits;
    it->seconds += static_cast<double>(stop - c.unix_ns) * 1e-9;
    previous = &c.scene;
  }
  return out;
}

std::vector<MemberStay> ComputeStays(std::vector<MemberEventRow> events) {
  std::stable_sort(events.begin(), events.end(),
                   [](const MemberEventRow& a, const MemberEventRow& b) { return a.unix_ns < b.unix_ns; });
  std::vector<MemberStay> stays;
  std::map<std::string, std::size_t> open;  // member_id -> index of its open stay
  for (const auto& e : events) {
    const auto it = open.find(e.member.member_id);
    if (e.change == MemberChange::kJoined) {
      if (it != open.end()) continue;  // a second join while present: the registry reports once
      open[e.member.member_id] = stays.size();
      stays.push_back(MemberStay{e.member, e.unix_ns, std::nullopt, "present at end"});
    } else if (it != open.end()) {
      MemberStay& s = stays[it->second];
      s.gone_unix_ns = e.unix_ns;
      s.how = ToString(e.change);
      open.erase(it);
    }
  }
  return stays;
}

namespace {

std::uint64_t U64(std::int64_t v) { return v < 0 ? 0 : static_cast<std::uint64_t>(v); }

std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string Format(const char* format, ...) {
  char text[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(text, sizeof text, format, args);
  va_end(args);
  return text;
}

std::string UtcTime(std::uint64_t unix_ns) {
  const std::time_t seconds = static_cast<std::time_t>(unix_ns / 1000000000ULL);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char text[64];
  std::strftime(text, sizeof text, "%Y-%m-%d %H:%M:%S", &tm);
  return Format("%s.%03u UTC", text, static_cast<unsigned>((unix_ns / 1000000ULL) % 1000ULL));
}

double Seconds(std::uint64_t from, std::uint64_t to) {
  return to >= from ? static_cast<double>(to - from) * 1e-9 : -static_cast<double>(from - to) * 1e-9;
}

// Opens a log for reading: a missing file, a directory, an empty file or another kind of
// database is a SessionLogError that says which.
std::unique_ptr<sqlite::Db> OpenForReading(const std::filesystem::path& file) {
  std::error_code ec;
  const auto status = std::filesystem::status(file, ec);
  if (!std::filesystem::exists(status)) throw SessionLogError(file.string() + ": no such file");
  if (std::filesystem::is_directory(status)) throw SessionLogError(file.string() + ": is a directory, not a session log");
  if (std::filesystem::file_size(file, ec) == 0 && !ec) {
    throw SessionLogError(file.string() + ": empty file, not a session log");
  }
  auto db = std::make_unique<sqlite::Db>(file, SQLITE_OPEN_READONLY);
  db->Check(sqlite3_busy_timeout(db->get(), 2000), "setting the busy timeout");
  const std::int64_t app = db->QueryInt("PRAGMA application_id", "reading the application id");
  const std::int64_t version = db->QueryInt("PRAGMA user_version", "reading the schema version");
  if (app != SessionLog::kApplicationId) {
    throw SessionLogError(file.string() + ": not a handshare session log (application_id " + std::to_string(app) + ")");
  }
  if (version < 1 || version > SessionLog::kSchemaVersion) {
    throw SessionLogError(file.string() + ": session log schema version " + std::to_string(version) +
                          " is not one this build reads (1.." + std::to_string(SessionLog::kSchemaVersion) + ")");
  }
  return db;
}

std::vector<SessionSummary> ReadSessions(sqlite::Db& db) {
  sqlite::Statement s(db,
                      "SELECT id, name, domain_id, host, pid, started_unix_ns, last_seen_unix_ns, ended_unix_ns, "
                      "dropped_rows FROM sessions ORDER BY id",
                      "reading the sessions");
  std::vector<SessionSummary> out;
  while (s.Step()) {
    SessionSummary x;
    x.id = s.Int(0);
    x.name = s.Text(1);
    x.domain_id = static_cast<int>(s.Int(2));
    x.host = s.Text(3);
    x.pid = s.Int(4);
    x.started_unix_ns = U64(s.Int(5));
    x.last_seen_unix_ns = U64(s.Int(6));
    if (!s.IsNull(7)) x.ended_unix_ns = U64(s.Int(7));
    x.dropped_rows = U64(s.Int(8));
    out.push_back(x);
  }
  return out;
}

MemberChange ChangeFromString(const sqlite::Db& db, const std::string& text) {
  for (MemberChange c : {MemberChange::kJoined, MemberChange::kLeft, MemberChange::kLost}) {
    if (text == ToString(c)) return c;
  }
  throw SessionLogError(db.file_name() + ": unknown member change '" + text + "'");
}

std::string CsvField(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c;
  }
  return out + "\"";
}

// Version 4's tables: the controls' kinds, the visitors' turns and questionnaires. A log of an
// older version has none: every control's kind is unknown, and there are no turns or answers.
void ReadVisits(sqlite::Db& db, std::int64_t id, const std::vector<ControlRecord>& controls, SessionReport& report) {
  std::map<std::string, scene::ControlType> kinds;
  std::vector<AnswerRow> answers;
  if (db.QueryInt("PRAGMA user_version", "reading the schema version") >= 4) {
    {
      sqlite::Statement s(db, "SELECT control_id, kind FROM control_kinds WHERE session_id = ?1",
                          "reading the controls' kinds");
      s.Bind(1, id);
      while (s.Step()) {
        const std::string kind = s.Text(1);
        const auto k = controls::ControlTypeFromString(kind);
        if (!k) throw SessionLogError(db.file_name() + ": unknown kind of control '" + kind + "'");
        kinds[s.Text(0)] = *k;
      }
    }
    {
      sqlite::Statement s(db,
                          "SELECT started_unix_ns, ended_unix_ns, member_id, user FROM visit_turns "
                          "WHERE session_id = ?1 ORDER BY ended_unix_ns, id",
                          "reading the visitors' turns");
      s.Bind(1, id);
      while (s.Step()) report.turns.push_back(TurnRecord{U64(s.Int(0)), U64(s.Int(1)), s.Text(2), s.Text(3)});
    }
    {
      sqlite::Statement s(db,
                          "SELECT visitor, control_kind, question, score FROM visit_answers "
                          "WHERE session_id = ?1 ORDER BY id",
                          "reading the questionnaires");
      s.Bind(1, id);
      while (s.Step()) {
        const auto kind = controls::ControlTypeFromString(s.Text(1));
        const auto question = controls::VisitQuestionFromString(s.Text(2));
        if (!kind || !question) {
          throw SessionLogError(db.file_name() + ": unknown questionnaire row '" + s.Text(1) + "', '" + s.Text(2) + "'");
        }
        answers.push_back(AnswerRow{s.Text(0), *kind, *question, static_cast<int>(s.Int(3))});
      }
    }
    {
      sqlite::Statement s(db,
                          "SELECT count(*) FROM (SELECT DISTINCT unix_ns, visitor, sent_by FROM visit_answers "
                          "WHERE session_id = ?1)",
                          "counting the questionnaires");
      s.Bind(1, id);
      if (s.Step()) report.questionnaires = U64(s.Int(0));
    }
  }
  report.kinds = ComputeKindStats(controls, kinds);
  report.questionnaire = ComputeQuestionnaire(answers);
}

// Version 5's loop statistics: per node, its samples summed up and its newest sample.
std::vector<StationStats> ReadStations(sqlite::Db& db, std::int64_t id) {
  std::vector<StationStats> out;
  if (db.QueryInt("PRAGMA user_version", "reading the schema version") < 5) return out;
  sqlite::Statement s(db,
                      "SELECT a.node, a.n, a.first, a.last, a.rate_mean, a.rate_min, a.jitter_max, a.bytes_mean, "
                      "l.unix_ns, l.rate_hz, l.jitter_p50_us, l.jitter_p99_us, l.jitter_max_us, l.step_p50_us, "
                      "l.step_p99_us, l.steps, l.overruns, l.resyncs, l.faults, l.samples_dropped, l.deadline_misses, "
                      "l.sent_bytes_per_s FROM (SELECT node, count(*) AS n, min(unix_ns) AS first, max(unix_ns) AS last, "
                      "avg(rate_hz) AS rate_mean, min(rate_hz) AS rate_min, max(jitter_p99_us) AS jitter_max, "
                      "avg(sent_bytes_per_s) AS bytes_mean, max(id) AS last_id FROM loop_statistics "
                      "WHERE session_id = ?1 GROUP BY node) a JOIN loop_statistics l ON l.id = a.last_id ORDER BY a.node",
                      "reading the stations' loop statistics");
  s.Bind(1, id);
  while (s.Step()) {
    StationStats st;
    st.node = s.Text(0);
    st.samples = U64(s.Int(1));
    st.first_unix_ns = U64(s.Int(2));
    st.last_unix_ns = U64(s.Int(3));
    st.rate_mean_Hz = s.Double(4);
    st.rate_min_Hz = s.Double(5);
    st.jitter_p99_max_us = s.Double(6);
    st.sent_bytes_per_s_mean = s.Double(7);
    LoopRecord& l = st.last;
    l.node = st.node;
    l.unix_ns = U64(s.Int(8));
    l.rate_Hz = s.Double(9);
    l.jitter_p50_us = s.Double(10);
    l.jitter_p99_us = s.Double(11);
    l.jitter_max_us = s.Double(12);
    l.step_p50_us = s.Double(13);
    l.step_p99_us = s.Double(14);
    l.steps = U64(s.Int(15));
    l.overruns = U64(s.Int(16));
    l.resyncs = U64(s.Int(17));
    l.faults = U64(s.Int(18));
    l.samples_dropped = U64(s.Int(19));
    l.deadline_misses = U64(s.Int(20));
    l.sent_bytes_per_s = s.Double(21);
    out.push_back(std::move(st));
  }
  return out;
}

}  // namespace

std::vector<SessionSummary> ListSessions(const std::filesystem::path& file) {
  auto db = OpenForReading(file);
  return ReadSessions(*db);
}

SessionReport ReadReport(const std::filesystem::path& file, std::optional<std::int64_t> session_id) {
  auto db = OpenForReading(file);
  // One read transaction: a consistent snapshot while a server may still be writing.
  db->Exec("BEGIN", "starting a read transaction");
  SessionReport report;
  report.file = file;
  const auto sessions = ReadSessions(*db);
  report.sessions_in_file = sessions.size();
  if (sessions.empty()) throw SessionLogError(file.string() + ": the log holds no sessions");
  if (session_id) {
    const auto it = std::find_if(sessions.begin(), sessions.end(),
                                 [&](const SessionSummary& s) { return s.id == *session_id; });
    if (it == sessions.end()) {
      throw SessionLogError(file.string() + ": no session " + std::to_string(*session_id) + " (sessions " +
                            std::to_string(sessions.front().id) + ".." + std::to_string(sessions.back().id) + ")");
    }
    report.session = *it;
  } else {
    report.session = sessions.back();
  }
  const std::int64_t id = report.session.id;

  std::vector<MemberEventRow> members;
  {
    sqlite::Statement s(*db,
                        "SELECT unix_ns, change, member_id, user, kind, device, pid FROM member_events "
                        "WHERE session_id = ?1 ORDER BY unix_ns, id",
                        "reading the member events");
    s.Bind(1, id);
    while (s.Step()) {
      members.push_back(MemberEventRow{U64(s.Int(0)), ChangeFromString(*db, s.Text(1)),
                                       Member{s.Text(2), s.Text(3), s.Text(4), s.Text(5), s.Int(6)}});
    }
  }
  report.members = ComputeStays(std::move(members));

  std::vector<SceneChange> scenes;
  {
    sqlite::Statement s(*db, "SELECT unix_ns, scene, title FROM scene_changes WHERE session_id = ?1 ORDER BY unix_ns, id",
                        "reading the scene changes");
    s.Bind(1, id);
    while (s.Step()) scenes.push_back(SceneChange{U64(s.Int(0)), s.Text(1), s.Text(2)});
  }
  report.worlds = ComputeWorldTimes(std::move(scenes), report.session.end_unix_ns());

  std::vector<ControlRecord> controls;
  {
    sqlite::Statement s(*db,
                        "SELECT unix_ns, user, control_id, kind, value, error_m FROM control_events "
                        "WHERE session_id = ?1 ORDER BY unix_ns, id",
                        "reading the control events");
    s.Bind(1, id);
    while (s.Step()) {
      const std::string kind = s.Text(3);
      const auto k = EventKindFromLogName(kind);
      if (!k) throw SessionLogError(file.string() + ": unknown control event kind '" + kind + "'");
      ControlRecord r{U64(s.Int(0)), s.Text(1), s.Text(2), *k, s.Double(4), std::nullopt};
      if (!s.IsNull(5)) r.error_m = s.Double(5);
      controls.push_back(std::move(r));
    }
  }
  report.control_events = controls.size();
  report.controls = ComputeControlStats(controls);
  {
    sqlite::Statement s(*db, "SELECT count(*) FROM ownership_changes WHERE session_id = ?1",
                        "counting the ownership changes");
    s.Bind(1, id);
    if (s.Step()) report.ownership_changes = U64(s.Int(0));
  }
  ReadVisits(*db, id, controls, report);
  report.stations = ReadStations(*db, id);
  db->Exec("COMMIT", "ending the read transaction");
  return report;
}

void PrintReport(std::ostream& out, const SessionReport& r) {
  const SessionSummary& s = r.session;
  out << "session log " << r.file.string() << ": " << r.sessions_in_file << " session(s), showing #" << s.id << "\n";
  out << "session #" << s.id << " '" << s.name << "' on DDS domain " << s.domain_id << ", world_server pid " << s.pid
      << " on " << (s.host.empty() ? "?" : s.host) << "\n";
  out << "  started " << UtcTime(s.started_unix_ns) << "\n";
  if (s.ended_unix_ns) {
    out << "  ended   " << UtcTime(*s.ended_unix_ns)
        << Format("  (%.3f s)\n", Seconds(s.started_unix_ns, *s.ended_unix_ns));
  } else {
    out << "  not ended cleanly (server killed?); last seen " << UtcTime(s.last_seen_unix_ns)
        << Format("  (%.3f s)\n", Seconds(s.started_unix_ns, s.last_seen_unix_ns));
  }
  if (s.dropped_rows > 0) out << "  WARNING: " << s.dropped_rows << " rows were dropped (disk too slow)\n";

  out << "\nmembers: " << r.members.size() << " stay(s)\n";
  if (!r.members.empty()) {
    out << Format("  %-16s %-12s %-8s %10s %10s  %s\n", "user", "kind", "device", "joined [s]", "gone [s]", "how");
    for (const auto& m : r.members) {
      const std::string gone = m.gone_unix_ns ? Format("%10.3f", Seconds(s.started_unix_ns, *m.gone_unix_ns)) : "         -";
      out << Format("  %-16s %-12s %-8s %10.3f %s  %s\n", m.member.user.c_str(), m.member.kind.c_str(),
                    m.member.device.empty() ? "-" : m.member.device.c_str(),
                    Seconds(s.started_unix_ns, m.joined_unix_ns), gone.c_str(), m.how.c_str());
    }
  }

  double total = 0.0;
  for (const auto& w : r.worlds) total += w.seconds;
  out << "\ntime in each world\n";
  if (r.worlds.empty()) out << "  (no scene changes logged)\n";
  else out << Format("  %-20s %6s %10s %7s  %s\n", "world", "visits", "time [s]", "share", "title");
  for (const auto& w : r.worlds) {
    out << Format("  %-20s %6zu %10.3f %6.1f%%  %s\n", w.scene.c_str(), w.visits, w.seconds,
                  total > 0 ? 100.0 * w.seconds / total : 0.0, w.title.c_str());
  }

  out << "\ncontrols: " << r.control_events << " event(s); error = distance of a hit from the control's target "
      << "(hits that carry one); misses per user as in the paper's Table 4 (users = those who tried)\n";
  if (r.controls.empty()) {
    out << "  (no control events logged)\n";
  } else {
    out << Format("  %-16s %6s %7s %8s %10s %10s %6s %9s %7s\n", "control", "hits", "misses", "hit errs",
                  "mean [mm]", "sd [mm]", "users", "miss mean", "miss sd");
    for (const auto& c : r.controls) {
      out << Format("  %-16s %6zu %7zu %8zu %10.2f %10.2f %6zu %9.2f %7.2f\n", c.control_id.c_str(), c.hits,
                    c.misses, c.error_m.n, c.error_m.mean * 1e3, c.error_m.sd * 1e3, c.misses_per_user.n,
                    c.misses_per_user.mean, c.misses_per_user.sd);
    }
  }
  out << "\nownership changes: " << r.ownership_changes << "\n";

  out << "\ncontrols by kind (the paper's Table 4): the rows above summed over the controls of each kind\n";
  if (r.kinds.empty()) {
    out << "  (no control events logged)\n";
  } else {
    out << Format("  %-8s %8s %6s %7s %8s %10s %10s %6s %9s %7s\n", "kind", "controls", "hits", "misses", "hit errs",
                  "mean [mm]", "sd [mm]", "users", "miss mean", "miss sd");
    for (const auto& k : r.kinds) {
      out << Format("  %-8s %8zu %6zu %7zu %8zu %10.2f %10.2f %6zu %9.2f %7.2f\n", k.kind.c_str(), k.controls, k.hits,
                    k.misses, k.error_m.n, k.error_m.mean * 1e3, k.error_m.sd * 1e3, k.misses_per_user.n,
                    k.misses_per_user.mean, k.misses_per_user.sd);
    }
  }

  out << "\nvisitors' turns ended: " << r.turns.size() << "\n";
  if (!r.turns.empty()) {
    out << Format("  %-16s %10s %10s %10s\n", "user", "joined [s]", "ended [s]", "turn [s]");
    for (const auto& t : r.turns) {
      out << Format("  %-16s %10.3f %10.3f %10.3f\n", t.user.c_str(), Seconds(s.started_unix_ns, t.started_unix_ns),
                    Seconds(s.started_unix_ns, t.ended_unix_ns), Seconds(t.started_unix_ns, t.ended_unix_ns));
    }
  }

  out << "\nquestionnaire (the paper's Fig. 16 and Table 3): " << r.questionnaires
      << " questionnaire(s); scores 1 (least) to 7 (most)\n";
  out << Format("  %-8s %-13s %4s %6s %6s\n", "kind", "question", "n", "mean", "sd");
  for (const auto& q : r.questionnaire) {
    // No answer has no mean, one answer no spread: a dash, not a 0.00 that reads as a score.
    const std::string mean = q.score.n > 0 ? Format("%6.2f", q.score.mean) : "     -";
    const std::string sd = q.score.n > 1 ? Format("%6.2f", q.score.sd) : "     -";
    out << Format("  %-8s %-13s %4zu %s %s\n", controls::ToString(q.kind), controls::ToString(q.question),
                  q.score.n, mean.c_str(), sd.c_str());
  }

  out << "\nstations (loop statistics, about one sample a second a node; counts from the node's start, as of "
         "its last sample): "
      << r.stations.size() << "\n";
  if (!r.stations.empty()) {
    out << Format("  %-28s %7s %9s %9s %11s %8s %6s %9s %7s %10s\n", "node", "samples", "rate [Hz]", "min [Hz]",
                  "jit p99 max", "overruns", "faults", "deadlines", "dropped", "bytes/s");
    for (const auto& st : r.stations) {
      out << Format("  %-28s %7zu %9.1f %9.1f %8.0f us %8llu %6llu %9llu %7llu %10.0f\n", st.node.c_str(), st.samples,
                    st.rate_mean_Hz, st.rate_min_Hz, st.jitter_p99_max_us,
                    static_cast<unsigned long long>(st.last.overruns), static_cast<unsigned long long>(st.last.faults),
                    static_cast<unsigned long long>(st.last.deadline_misses),
                    static_cast<unsigned long long>(st.last.samples_dropped), st.sent_bytes_per_s_mean);
    }
  }
}

void PrintReportCsv(std::ostream& out, const SessionReport& r) {
  const SessionSummary& s = r.session;
  const std::string sid = std::to_string(s.id);
  auto row = [&](const char* section, const std::string& item, const char* field, const std::string& value) {
    out << sid << ',' << section << ',' << CsvField(item) << ',' << field << ',' << CsvField(value) << '\n';
  };
  out << "session,section,item,field,value\n";
  row("session", sid, "name", s.name);
  row("session", sid, "domain_id", std::to_string(s.domain_id));
  row("session", sid, "host", s.host);
  row("session", sid, "pid", std::to_string(s.pid));
  row("session", sid, "started_unix_ns", std::to_string(s.started_unix_ns));
  row("session", sid, "ended_unix_ns", s.ended_unix_ns ? std::to_string(*s.ended_unix_ns) : "");
  row("session", sid, "last_seen_unix_ns", std::to_string(s.last_seen_unix_ns));
  row("session", sid, "duration_s", Format("%.3f", Seconds(s.started_unix_ns, s.end_unix_ns())));
  row("session", sid, "dropped_rows", std::to_string(s.dropped_rows));
  std::map<std::string, int> stay_number;
  for (const auto& m : r.members) {
    const std::string item = m.member.member_id + "#" + std::to_string(++stay_number[m.member.member_id]);
    row("member", item, "user", m.member.user);
    row("member", item, "kind", m.member.kind);
    row("member", item, "device", m.member.device);
    row("member", item, "joined_s", Format("%.3f", Seconds(s.started_unix_ns, m.joined_unix_ns)));
    row("member", item, "gone_s", m.gone_unix_ns ? Format("%.3f", Seconds(s.started_unix_ns, *m.gone_unix_ns)) : "");
    row("member", item, "how", m.how);
  }
  for (const auto& w : r.worlds) {
    row("world", w.scene, "title", w.title);
    row("world", w.scene, "visits", std::to_string(w.visits));
    row("world", w.scene, "seconds", Format("%.3f", w.seconds));
  }
  // A Table 4 row's counts and summaries, the same fields per control and per kind.
  auto tally_rows = [&](const char* section, const std::string& item, const auto& t) {
    row(section, item, "hits", std::to_string(t.hits));
    row(section, item, "misses", std::to_string(t.misses));
    row(section, item, "released", std::to_string(t.released));
    row(section, item, "error_n", std::to_string(t.error_m.n));
    row(section, item, "error_mean_m", Format("%.6g", t.error_m.mean));
    row(section, item, "error_sd_m", Format("%.6g", t.error_m.sd));
    row(section, item, "users", std::to_string(t.misses_per_user.n));
    row(section, item, "misses_per_user_mean", Format("%.6g", t.misses_per_user.mean));
    row(section, item, "misses_per_user_sd", Format("%.6g", t.misses_per_user.sd));
  };
  for (const auto& c : r.controls) tally_rows("control", c.control_id, c);
  row("ownership", sid, "changes", std::to_string(r.ownership_changes));
  for (const auto& k : r.kinds) {
    row("control_kind", k.kind, "controls", std::to_string(k.controls));
    tally_rows("control_kind", k.kind, k);
  }
  std::map<std::string, int> turn_number;
  for (const auto& t : r.turns) {
    const std::string item = t.member_id + "#" + std::to_string(++turn_number[t.member_id]);
    row("turn", item, "user", t.user);
    row("turn", item, "joined_s", Format("%.3f", Seconds(s.started_unix_ns, t.started_unix_ns)));
    row("turn", item, "ended_s", Format("%.3f", Seconds(s.started_unix_ns, t.ended_unix_ns)));
  }
  row("questionnaire", sid, "count", std::to_string(r.questionnaires));
  for (const auto& q : r.questionnaire) {
    const std::string item = std::string(controls::ToString(q.kind)) + "/" + controls::ToString(q.question);
    row("questionnaire", item, "n", std::to_string(q.score.n));
    row("questionnaire", item, "mean", Format("%.6g", q.score.mean));
    row("questionnaire", item, "sd", Format("%.6g", q.score.sd));
  }
  for (const auto& st : r.stations) {
    const auto u = [](std::uint64_t v) { return std::to_string(v); };
    row("station", st.node, "samples", std::to_string(st.samples));
    row("station", st.node, "first_s", Format("%.3f", Seconds(s.started_unix_ns, st.first_unix_ns)));
    row("station", st.node, "last_s", Format("%.3f", Seconds(s.started_unix_ns, st.last_unix_ns)));
    row("station", st.node, "rate_mean_Hz", Format("%.6g", st.rate_mean_Hz));
    row("station", st.node, "rate_min_Hz", Format("%.6g", st.rate_min_Hz));
    row("station", st.node, "jitter_p99_max_us", Format("%.6g", st.jitter_p99_max_us));
    row("station", st.node, "sent_bytes_per_s_mean", Format("%.6g", st.sent_bytes_per_s_mean));
    row("station", st.node, "rate_Hz", Format("%.6g", st.last.rate_Hz));
    row("station", st.node, "steps", u(st.last.steps));
    row("station", st.node, "overruns", u(st.last.overruns));
    row("station", st.node, "resyncs", u(st.last.resyncs));
    row("station", st.node, "faults", u(st.last.faults));
    row("station", st.node, "samples_dropped", u(st.last.samples_dropped));
    row("station", st.node, "deadline_misses", u(st.last.deadline_misses));
    row("station", st.node, "sent_bytes_per_s", Format("%.6g", st.last.sent_bytes_per_s));
  }
}

}  // namespace handshare::server
