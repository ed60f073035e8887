#include "handshare/world_server/session_log.hpp"

#include <condition_variable>
#include <cstdio>
#include <mutex>
#include <thread>
#include <variant>
#include <vector>

#include "handshare/common/clock.hpp"
#include "session_schema.hpp"
#include "sqlite_db.hpp"

#include <nlohmann/json.hpp>

namespace handshare::server {

const char* LogName(controls::EventKind kind) {
  switch (kind) {
    case controls::EventKind::kPressed: return "pressed";
    case controls::EventKind::kReleased: return "released";
    case controls::EventKind::kMoved: return "moved";
    case controls::EventKind::kPageTurned: return "page_turned";
    case controls::EventKind::kMissed: return "missed";
    case controls::EventKind::kOpened: return "opened";
    case controls::EventKind::kMoving: return "moving";  // not logged: motion, not an event of the session
  }
  return "?";
}

std::optional<controls::EventKind> EventKindFromLogName(std::string_view text) {
  using controls::EventKind;
  for (EventKind k : {EventKind::kPressed, EventKind::kReleased, EventKind::kMoved, EventKind::kPageTurned,
                      EventKind::kMissed, EventKind::kOpened}) {
    if (text == LogName(k)) return k;
  }
  return std::nullopt;
}

namespace {

struct MemberRow {
  std::uint64_t unix_ns;
  MemberChange change;
  Member member;
};
struct SceneRow {
  std::uint64_t unix_ns;
  std::string scene, title;
};
struct OwnershipRow {
  std::uint64_t unix_ns;
  std::string object_id, owner, reason;
};
struct EndRow {
  std::uint64_t unix_ns;
};
struct ForgetPosesRow {};
struct ForgetPlacesRow {};
struct AnswersRow {
  std::uint64_t unix_ns;
  std::string sent_by;
  controls::VisitAnswers answers;
};
struct ControlKindRow {
  std::string control_id;
  scene::ControlType kind;
};
using Row = std::variant<MemberRow, SceneRow, ControlRecord, OwnershipRow, EndRow, SessionState, ObjectPose, ForgetPosesRow,
                         ControlPlace, ForgetPlacesRow, TurnRecord, AnswersRow, ControlKindRow, LoopRecord>;

std::string BoardJson(const std::vector<scene::Message>& board) {
  nlohmann::json j = nlohmann::json::array();
  for (const auto& m : board) {
    j.push_back({{"language", m.language}, {"text", m.text}, {"next_action", m.next_action}, {"reading", m.reading}});
  }
  return j.dump();
}

std::int64_t Ns(std::uint64_t unix_ns) { return static_cast<std::int64_t>(unix_ns); }

std::string Hex(std::int64_t v) {
  char text[32];
  std::snprintf(text, sizeof text, "0x%08llx", static_cast<unsigned long long>(v) & 0xffffffffULL);
  return text;
}

// Opens the file and makes sure it is a handshare log of a schema this build writes,
// creating the schema in an empty file. A foreign database is left untouched.
void OpenSchema(sqlite::Db& db) {
  db.Check(sqlite3_busy_timeout(db.get(), 2000), "setting the busy timeout");
  if (sqlite3_db_readonly(db.get(), "main") == 1) {
    throw SessionLogError(db.file_name() + ": the session log is read-only (no write permission)");
  }
  const std::int64_t version = db.QueryInt("PRAGMA user_version", "reading the schema version");
  const std::int64_t app = db.QueryInt("PRAGMA application_id", "reading the application id");
  const std::int64_t tables = db.QueryInt("SELECT count(*) FROM sqlite_master", "reading the table list");
  if (app == 0 && version == 0 && tables == 0) {
    // WAL first (it cannot change inside a transaction), then the schema in one transaction
    // that IF NOT EXISTS makes safe against another process creating it at the same moment.
    const std::string mode = db.QueryText("PRAGMA journal_mode=WAL", "switching to WAL journal mode");
    if (mode != "wal") throw SessionLogError(db.file_name() + ": cannot use WAL journal mode (got '" + mode + "')");
    db.Exec("BEGIN IMMEDIATE", "starting the schema transaction");
    try {
      db.Exec(schema::kCreateV1, "creating the schema");
      db.Exec(schema::kStampV1, "writing the schema version");
      db.Exec(schema::kMigrateV1ToV2, "creating the schema's version 2");
      db.Exec(schema::kMigrateV2ToV3, "creating the schema's version 3");
      db.Exec(schema::kMigrateV3ToV4, "creating the schema's version 4");
      db.Exec(schema::kMigrateV4ToV5, "creating the schema's version 5");
      db.Exec("COMMIT", "committing the schema");
    } catch (...) {
      sqlite3_exec(db.get(), "ROLLBACK", nullptr, nullptr, nullptr);  // the first error is the one to report
      throw;
    }
    return;
  }
  if (app != SessionLog::kApplicationId) {
    throw SessionLogError(db.file_name() + ": not a handshare session log (a SQLite database with application_id " +
                          Hex(app) + " and " + std::to_string(tables) + " schema entries)");
  }
  if (version > SessionLog::kSchemaVersion) {
    throw SessionLogError(db.file_name() + ": session log schema version " + std::to_string(version) +
                          " is newer than this build's (" + std::to_string(SessionLog::kSchemaVersion) + ")");
  }
  if (version < 1) throw SessionLogError(db.file_name() + ": session log without a schema version");
  const std::string mode = db.QueryText("PRAGMA journal_mode=WAL", "switching to WAL journal mode");
  if (mode != "wal") throw SessionLogError(db.file_name() + ": cannot use WAL journal mode (got '" + mode + "')");
  if (version < SessionLog::kSchemaVersion) {
    // Every row stays; the version is read again inside the transaction, so two servers
    // opening one old log at once migrate it once.
    db.Exec("BEGIN IMMEDIATE", "starting the migration to schema version 5");
    try {
      const std::int64_t now = db.QueryInt("PRAGMA user_version", "reading the schema version");
      if (now == 1) db.Exec(schema::kMigrateV1ToV2, "migrating the session log to schema version 2");
      if (now <= 2) db.Exec(schema::kMigrateV2ToV3, "migrating the session log to schema version 3");
      if (now <= 3) db.Exec(schema::kMigrateV3ToV4, "migrating the session log to schema version 4");
      if (now <= 4) db.Exec(schema::kMigrateV4ToV5, "migrating the session log to schema version 5");
      db.Exec("COMMIT", "committing the migration to schema version 5");
    } catch (...) {
      sqlite3_exec(db.get(), "ROLLBACK", nullptr, nullptr, nullptr);
      throw;
    }
  }
}

}  // namespace

struct SessionLog::Impl {
  Impl(const std::filesystem::path& file, const SessionLogConfig& c) : db(file, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE), config(c) {}

  sqlite::Db db;
  SessionLogConfig config;
  std::int64_t session_id = 0;

  std::mutex mutex;
  std::condition_variable wake;       // the writer: rows to flush, or stop
  std::condition_variable committed;  // Flush(): the writer caught up
  std::vector<Row> queue;
  std::uint64_t enqueued = 0, done = 0, flush_target = 0;
  std::uint64_t dropped = 0;
  bool ended = false, stop = false;
  std::string error;
  std::thread writer;

  void Push(Row row) {
    std::lock_guard lock(mutex);
    if (!error.empty() || stop) return;
    if (queue.size() >= config.max_queued_rows) {
      ++dropped;
      return;
    }
    if (std::holds_alternative<EndRow>(row)) {
      if (ended) return;
      ended = true;
    }
    queue.push_back(std::move(row));
    ++enqueued;
  }

  // Prepared in the constructor, in the caller's thread, so a broken file fails there; the
  // writer thread owns the connection from then on.
  std::optional<sqlite::Statement> member, scene, control, owner, end, seen, state, pose, forget, place, forget_places,
      turn, answer, kind, loop;

  void Prepare() {
    member.emplace(db, schema::kInsertMember, "inserting a member event");
    scene.emplace(db, schema::kInsertScene, "inserting a scene change");
    control.emplace(db, schema::kInsertControl, "inserting a control event");
    owner.emplace(db, schema::kInsertOwnership, "inserting an ownership change");
    end.emplace(db, schema::kUpdateEnd, "writing the session end");
    seen.emplace(db, schema::kUpdateSeen, "writing the session's last-seen time");
    state.emplace(db, schema::kUpsertState, "writing the session state");
    pose.emplace(db, schema::kUpsertPose, "writing an object pose");
    forget.emplace(db, "DELETE FROM object_poses WHERE session_id = ?1", "forgetting the object poses");
    place.emplace(db, schema::kUpsertControlState, "writing a control's place");
    forget_places.emplace(db, "DELETE FROM control_states WHERE session_id = ?1", "forgetting the controls' places");
    turn.emplace(db, schema::kInsertTurn, "inserting a visitor's turn");
    answer.emplace(db, schema::kInsertAnswer, "inserting a questionnaire's answer");
    kind.emplace(db, schema::kUpsertControlKind, "writing a control's kind");
    loop.emplace(db, schema::kInsertLoop, "inserting a station's loop statistics");
  }

  void WriterLoop() {
    std::vector<Row> batch;
    auto last_seen = std::chrono::steady_clock::now();
    std::unique_lock lock(mutex);
    for (;;) {
      wake.wait_for(lock, config.flush_period, [&] { return stop || flush_target > done; });
      batch.clear();
      batch.swap(queue);
      const std::uint64_t target = enqueued;
      const bool stopping = stop;
      const std::uint64_t dropped_now = dropped;
      const bool healthy = error.empty();
      lock.unlock();
      // A heartbeat once a second even when idle, so a killed server's log still says until
      // when the session ran.
      const auto now = std::chrono::steady_clock::now();
      const bool heartbeat = now - last_seen >= std::chrono::seconds(1);
      std::string failure;
      if (healthy && (!batch.empty() || heartbeat || stopping)) {
        try {
          Commit(batch, dropped_now);
          last_seen = now;
        } catch (const SessionLogError& e) {
          failure = e.what();
        }
      }
      lock.lock();
      if (!failure.empty() && error.empty()) error = failure;
      done = target;
      committed.notify_all();
      if (stopping && queue.empty()) return;
    }
  }

  void Commit(const std::vector<Row>& batch, std::uint64_t dropped_now) {
    db.Exec("BEGIN IMMEDIATE", "starting a write transaction");
    try {
      for (const Row& row : batch) {
        if (const auto* m = std::get_if<MemberRow>(&row)) {
          member->Bind(1, session_id).Bind(2, Ns(m->unix_ns)).Bind(3, std::string_view(ToString(m->change)))
              .Bind(4, m->member.member_id).Bind(5, m->member.user).Bind(6, m->member.kind)
              .Bind(7, m->member.device).Bind(8, m->member.pid);
          member->Step();
          member->Reset();
        } else if (const auto* s = std::get_if<SceneRow>(&row)) {
          scene->Bind(1, session_id).Bind(2, Ns(s->unix_ns)).Bind(3, s->scene).Bind(4, s->title);
          scene->Step();
          scene->Reset();
        } else if (const auto* c = std::get_if<ControlRecord>(&row)) {
          control->Bind(1, session_id).Bind(2, Ns(c->unix_ns)).Bind(3, c->user).Bind(4, c->control_id)
              .Bind(5, std::string_view(LogName(c->kind))).Bind(6, c->value).Bind(7, c->error_m);
          control->Step();
          control->Reset();
        } else if (const auto* o = std::get_if<OwnershipRow>(&row)) {
          owner->Bind(1, session_id).Bind(2, Ns(o->unix_ns)).Bind(3, o->object_id).Bind(4, o->owner)
              .Bind(5, o->reason);
          owner->Step();
          owner->Reset();
        } else if (const auto* st = std::get_if<SessionState>(&row)) {
          const auto& g = st->gravity_W_m_per_s2;
          state->Bind(1, session_id).Bind(2, Ns(st->unix_ns)).Bind(3, st->scene).Bind(4, st->title)
              .Bind(5, static_cast<std::int64_t>(st->revision)).Bind(6, g[0]).Bind(7, g[1]).Bind(8, g[2])
              .Bind(9, Ns(st->epoch_unix_ns)).Bind(10, static_cast<std::int64_t>(st->message_id))
              .Bind(11, BoardJson(st->board));
          state->Step();
          state->Reset();
        } else if (const auto* p = std::get_if<ObjectPose>(&row)) {
          pose->Bind(1, session_id).Bind(2, p->object_id).Bind(3, Ns(p->unix_ns)).Bind(4, p->owner)
              .Bind(5, p->p_WO_m[0]).Bind(6, p->p_WO_m[1]).Bind(7, p->p_WO_m[2]).Bind(8, p->q_WO_wxyz[0])
              .Bind(9, p->q_WO_wxyz[1]).Bind(10, p->q_WO_wxyz[2]).Bind(11, p->q_WO_wxyz[3]);
          pose->Step();
          pose->Reset();
        } else if (std::holds_alternative<ForgetPosesRow>(row)) {
          forget->Bind(1, session_id);
          forget->Step();
          forget->Reset();
        } else if (const auto* cp = std::get_if<ControlPlace>(&row)) {
          place->Bind(1, session_id).Bind(2, cp->control_id).Bind(3, Ns(cp->unix_ns)).Bind(4, cp->scene)
              .Bind(5, static_cast<std::int64_t>(cp->index)).Bind(6, static_cast<std::int64_t>(cp->engaged ? 1 : 0))
              .Bind(7, cp->user).Bind(8, static_cast<std::int64_t>(cp->changes));
          place->Step();
          place->Reset();
        } else if (std::holds_alternative<ForgetPlacesRow>(row)) {
          forget_places->Bind(1, session_id);
          forget_places->Step();
          forget_places->Reset();
        } else if (const auto* t = std::get_if<TurnRecord>(&row)) {
          turn->Bind(1, session_id).Bind(2, Ns(t->started_unix_ns)).Bind(3, Ns(t->ended_unix_ns)).Bind(4, t->member_id)
              .Bind(5, t->user);
          turn->Step();
          turn->Reset();
        } else if (const auto* a = std::get_if<AnswersRow>(&row)) {
          // One row per answered score: the report groups them by kind and question in SQL's order.
          for (std::size_t k = 0; k < controls::kVisitControlKinds; ++k) {
            for (std::size_t q = 0; q < controls::kVisitQuestions; ++q) {
              const int score = a->answers.scores[k][q];
              if (score == 0) continue;
              answer->Bind(1, session_id).Bind(2, Ns(a->unix_ns)).Bind(3, a->answers.visitor).Bind(4, a->sent_by)
                  .Bind(5, std::string_view(controls::ToString(static_cast<scene::ControlType>(k))))
                  .Bind(6, std::string_view(controls::ToString(static_cast<controls::VisitQuestion>(q))))
                  .Bind(7, static_cast<std::int64_t>(score));
              answer->Step();
              answer->Reset();
            }
          }
        } else if (const auto* ck = std::get_if<ControlKindRow>(&row)) {
          kind->Bind(1, session_id).Bind(2, ck->control_id).Bind(3, std::string_view(controls::ToString(ck->kind)));
          kind->Step();
          kind->Reset();
        } else if (const auto* l = std::get_if<LoopRecord>(&row)) {
          const auto n = [](std::uint64_t v) { return static_cast<std::int64_t>(v); };
          loop->Bind(1, session_id).Bind(2, Ns(l->unix_ns)).Bind(3, l->node).Bind(4, l->rate_Hz)
              .Bind(5, l->jitter_p50_us).Bind(6, l->jitter_p99_us).Bind(7, l->jitter_max_us).Bind(8, l->step_p50_us)
              .Bind(9, l->step_p99_us).Bind(10, n(l->steps)).Bind(11, n(l->overruns)).Bind(12, n(l->resyncs))
              .Bind(13, n(l->faults)).Bind(14, n(l->samples_dropped)).Bind(15, n(l->deadline_misses))
              .Bind(16, l->sent_bytes_per_s);
          loop->Step();
          loop->Reset();
        } else if (const auto* e = std::get_if<EndRow>(&row)) {
          end->Bind(1, Ns(e->unix_ns)).Bind(2, session_id);
          end->Step();
          end->Reset();
        }
      }
      seen->Bind(1, Ns(common::UnixNowNs())).Bind(2, static_cast<std::int64_t>(dropped_now)).Bind(3, session_id);
      seen->Step();
      seen->Reset();
      db.Exec("COMMIT", "committing a write transaction");
    } catch (...) {
      sqlite3_exec(db.get(), "ROLLBACK", nullptr, nullptr, nullptr);  // the first error is the one to report
      throw;
    }
  }
};

SessionLog::SessionLog(const std::filesystem::path& file, const SessionStart& start, SessionLogConfig config)
    : file_(file), impl_(std::make_unique<Impl>(file, config)) {
  sqlite::Db& db = impl_->db;
  OpenSchema(db);
  db.Check(sqlite3_busy_timeout(db.get(), static_cast<int>(config.busy_timeout.count())), "setting the busy timeout");
  db.Exec("PRAGMA synchronous=NORMAL", "setting synchronous=NORMAL");
  db.Exec("PRAGMA foreign_keys=ON", "enabling foreign keys");
  {
    sqlite::Statement insert(db, schema::kInsertSession, "inserting the session");
    insert.Bind(1, start.name).Bind(2, static_cast<std::int64_t>(start.domain_id)).Bind(3, start.host)
        .Bind(4, start.pid).Bind(5, static_cast<std::int64_t>(kSchemaVersion)).Bind(6, Ns(start.unix_ns))
        .Bind(7, Ns(start.unix_ns));
    insert.Step();
  }
  session_id_ = sqlite3_last_insert_rowid(db.get());
  impl_->session_id = session_id_;
  if (start.resumed_from != 0) {
    sqlite::Statement resumed(db, schema::kUpdateResumedFrom, "writing the session it resumes");
    resumed.Bind(1, start.resumed_from).Bind(2, session_id_);
    resumed.Step();
  }
  impl_->Prepare();
  impl_->writer = std::thread([impl = impl_.get()] {
    try {
      impl->WriterLoop();
    } catch (const SessionLogError& e) {
      std::lock_guard lock(impl->mutex);
      if (impl->error.empty()) impl->error = e.what();
      impl->stop = true;
      impl->done = impl->enqueued;
      impl->committed.notify_all();
    }
  });
}

SessionLog::~SessionLog() {
  End(common::UnixNowNs());
  {
    std::lock_guard lock(impl_->mutex);
    impl_->stop = true;
  }
  impl_->wake.notify_all();
  impl_->writer.join();
  // A finished log is one file: leaving WAL mode checkpoints and removes the -wal and -shm
  // files, which a reader that opens the log later read-only (session_report) could not remove.
  // With another connection open (a live report) the mode stays WAL; nothing is lost either way,
  // and the next server to open the log switches it back to WAL.
  if (impl_->error.empty()) {
    for (auto* statement : {&impl_->member, &impl_->scene, &impl_->control, &impl_->owner, &impl_->end, &impl_->seen,
                            &impl_->state, &impl_->pose, &impl_->forget}) {
      statement->reset();  // finalized before the mode changes
    }
    try {
      impl_->db.QueryText("PRAGMA journal_mode=DELETE", "leaving WAL journal mode");
    } catch (const SessionLogError&) {
    }
  }
}

void SessionLog::OnMember(MemberChange change, const Member& member, std::uint64_t unix_ns) {
  impl_->Push(MemberRow{unix_ns, change, member});
  // Rows are committed on the writer's period; waking it per row would only add context switches.
}

void SessionLog::OnSceneChange(const std::string& scene, const std::string& title, std::uint64_t unix_ns) {
  impl_->Push(SceneRow{unix_ns, scene, title});
}

void SessionLog::OnControlEvent(const ControlRecord& event) {
  // A hand moving a control (up to 25 reports a second) is not an event of the session.
  if (event.kind == controls::EventKind::kMoving) return;
  impl_->Push(event);
}

void SessionLog::OnOwnership(const std::string& object_id, const std::string& owner, const std::string& reason,
                             std::uint64_t unix_ns) {
  impl_->Push(OwnershipRow{unix_ns, object_id, owner, reason});
}

void SessionLog::OnState(const SessionState& state) { impl_->Push(state); }

void SessionLog::OnObjectPose(const ObjectPose& pose) { impl_->Push(pose); }

void SessionLog::ForgetObjectPoses() { impl_->Push(ForgetPosesRow{}); }

void SessionLog::OnControlPlace(const ControlPlace& place) { impl_->Push(place); }

void SessionLog::OnTurnEnded(const TurnRecord& turn) { impl_->Push(turn); }

void SessionLog::OnVisitAnswers(const std::string& sent_by, const controls::VisitAnswers& answers, std::uint64_t unix_ns) {
  impl_->Push(AnswersRow{unix_ns, sent_by, answers});
}

void SessionLog::OnControlKinds(const scene::Scene& scene) {
  for (const auto& c : scene.controls) impl_->Push(ControlKindRow{c.id, c.type});
}

void SessionLog::OnLoopStatistics(const LoopRecord& loop) { impl_->Push(loop); }

void SessionLog::ForgetControlPlaces() { impl_->Push(ForgetPlacesRow{}); }

void SessionLog::End(std::uint64_t unix_ns) { impl_->Push(EndRow{unix_ns}); }

std::optional<ResumePoint> FindResumePoint(const std::filesystem::path& file, const std::string& session,
                                           std::uint64_t now_unix_ns, std::uint64_t max_age_ns) {
  std::error_code ec;
  if (!std::filesystem::exists(file, ec) || std::filesystem::file_size(file, ec) == 0) return std::nullopt;
  sqlite::Db db(file, SQLITE_OPEN_READONLY);
  db.Check(sqlite3_busy_timeout(db.get(), 2000), "setting the busy timeout");
  if (db.QueryInt("PRAGMA application_id", "reading the application id") != SessionLog::kApplicationId) {
    throw SessionLogError(file.string() + ": not a handshare session log");
  }
  const std::int64_t version = db.QueryInt("PRAGMA user_version", "reading the schema version");
  if (version < 2) return std::nullopt;  // no states
  ResumePoint r;
  {
    sqlite::Statement s(db,
                        "SELECT s.id, s.last_seen_unix_ns, st.unix_ns, st.scene, st.title, st.revision, st.gravity_x, "
                        "st.gravity_y, st.gravity_z, st.epoch_unix_ns, st.message_id, st.board_json "
                        "FROM sessions s JOIN session_state st ON st.session_id = s.id "
                        "WHERE s.name = ?1 ORDER BY s.id DESC LIMIT 1",
                        "reading the newest session's state");
    s.Bind(1, session);
    if (!s.Step()) return std::nullopt;
    r.session_id = s.Int(0);
    r.last_seen_unix_ns = static_cast<std::uint64_t>(s.Int(1));
    SessionState& st = r.state;
    st.unix_ns = static_cast<std::uint64_t>(s.Int(2));
    st.scene = s.Text(3);
    st.title = s.Text(4);
    st.revision = static_cast<std::uint32_t>(s.Int(5));
    for (int k = 0; k < 3; ++k) st.gravity_W_m_per_s2[k] = s.Double(6 + k);
    st.epoch_unix_ns = static_cast<std::uint64_t>(s.Int(9));
    st.message_id = static_cast<std::uint32_t>(s.Int(10));
    try {
      for (const auto& m : nlohmann::json::parse(s.Text(11))) {
        // A log written before boards had readings resumes with none (value(): "" when absent).
        st.board.push_back({m.at("language").get<std::string>(), m.at("text").get<std::string>(),
                            m.at("next_action").get<std::string>(), m.value("reading", std::string())});
      }
    } catch (const nlohmann::json::exception& e) {
      throw SessionLogError(file.string() + ": session " + std::to_string(r.session_id) + ": bad board_json: " + e.what());
    }
  }
  // The newest session of that name must be the one that never ended, and recent.
  {
    sqlite::Statement s(db, "SELECT ended_unix_ns IS NULL FROM sessions WHERE id = ?1", "reading the session end");
    s.Bind(1, r.session_id);
    if (!s.Step() || s.Int(0) == 0) return std::nullopt;
    sqlite::Statement newer(db, "SELECT count(*) FROM sessions WHERE name = ?1 AND id > ?2",
                            "looking for a newer session");
    newer.Bind(1, session).Bind(2, r.session_id);
    if (newer.Step() && newer.Int(0) > 0) return std::nullopt;
  }
  if (now_unix_ns > r.last_seen_unix_ns && now_unix_ns - r.last_seen_unix_ns > max_age_ns) return std::nullopt;
  sqlite::Statement s(db,
                      "SELECT object_id, owner, unix_ns, px, py, pz, qw, qx, qy, qz FROM object_poses "
                      "WHERE session_id = ?1 ORDER BY object_id",
                      "reading the object poses");
  s.Bind(1, r.session_id);
  while (s.Step()) {
    ObjectPose p;
    p.object_id = s.Text(0);
    p.owner = s.Text(1);
    p.unix_ns = static_cast<std::uint64_t>(s.Int(2));
    for (int k = 0; k < 3; ++k) p.p_WO_m[k] = s.Double(3 + k);
    for (int k = 0; k < 4; ++k) p.q_WO_wxyz[k] = s.Double(6 + k);
    r.poses.push_back(std::move(p));
  }
  if (version < 3) return r;  // no places
  sqlite::Statement c(db,
                      "SELECT control_id, scene, unix_ns, idx, engaged, user, changes FROM control_states "
                      "WHERE session_id = ?1 ORDER BY control_id",
                      "reading the controls' places");
  c.Bind(1, r.session_id);
  while (c.Step()) {
    ControlPlace p;
    p.control_id = c.Text(0);
    p.scene = c.Text(1);
    p.unix_ns = static_cast<std::uint64_t>(c.Int(2));
    p.index = static_cast<std::int32_t>(c.Int(3));
    p.engaged = c.Int(4) != 0;
    p.user = c.Text(5);
    p.changes = static_cast<std::uint32_t>(c.Int(6));
    r.controls.push_back(std::move(p));
  }
  return r;
}

void SessionLog::Flush() {
  std::unique_lock lock(impl_->mutex);
  impl_->flush_target = impl_->enqueued;
  impl_->wake.notify_all();
  impl_->committed.wait(lock, [&] { return impl_->done >= impl_->flush_target || !impl_->error.empty(); });
  if (!impl_->error.empty()) throw SessionLogError(impl_->error);
}

std::string SessionLog::error() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->error;
}

std::uint64_t SessionLog::dropped_rows() const {
  std::lock_guard lock(impl_->mutex);
  return impl_->dropped;
}

}  // namespace handshare::server
