#pragma once
// The session log's schema (PRAGMA user_version, application_id "HSLG"). Times are wall-clock
// ns since the Unix epoch. A change of schema gets a new version number and a migration in
// OpenSchema; a reader refuses versions newer than it knows.
//   version 1: sessions, member_events, scene_changes, control_events, ownership_changes.
//   version 2: control_events may say 'opened' (a book's cover); session_state and
//              object_poses hold where a session is, so a restarted server resumes it;
//              sessions.resumed_from names the session a resumed one continues.
//   version 3: control_states holds where each control of the current world settled, so a
//              restarted server publishes them again (a node joining later builds them there).
//   version 4: visit_turns (a visitor's turn ended after --visit-minutes), visit_answers (the
//              questionnaire at its end, the paper's Fig. 16) and control_kinds (each control's
//              kind, for the paper's Table 4 by kind of control).
//   version 5: loop_statistics (every station's LoopStatistics sample as the world server took
//              it: haptic nodes, screens, guides; what the operator's page showed).
namespace handshare::server::schema {

inline constexpr const char* kCreateV1 = R"sql(
CREATE TABLE IF NOT EXISTS sessions(
  id                INTEGER PRIMARY KEY,
  name              TEXT    NOT NULL,            -- the DDS session (partition)
  domain_id         INTEGER NOT NULL,
  host              TEXT    NOT NULL,
  pid               INTEGER NOT NULL,
  schema_version    INTEGER NOT NULL,
  started_unix_ns   INTEGER NOT NULL,
  last_seen_unix_ns INTEGER NOT NULL,            -- heartbeat: the writer's last commit
  ended_unix_ns     INTEGER,                     -- NULL: not ended cleanly (server killed)
  dropped_rows      INTEGER NOT NULL DEFAULT 0   -- rows lost because the disk fell behind
);
CREATE TABLE IF NOT EXISTS member_events(
  id         INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  unix_ns    INTEGER NOT NULL,
  change     TEXT    NOT NULL CHECK (change IN ('joined', 'left', 'lost')),
  member_id  TEXT    NOT NULL,
  user       TEXT    NOT NULL,
  kind       TEXT    NOT NULL,                   -- haptic, graphics, audio_guide, world_server
  device     TEXT    NOT NULL,                   -- sim, hiro, replay, '' for non-haptic nodes
  pid        INTEGER NOT NULL
);
CREATE TABLE IF NOT EXISTS scene_changes(
  id         INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  unix_ns    INTEGER NOT NULL,
  scene      TEXT    NOT NULL,                   -- world name, e.g. solar_system
  title      TEXT    NOT NULL
);
CREATE TABLE IF NOT EXISTS control_events(
  id         INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  unix_ns    INTEGER NOT NULL,
  user       TEXT    NOT NULL,
  control_id TEXT    NOT NULL,
  kind       TEXT    NOT NULL CHECK (kind IN ('pressed', 'released', 'moved', 'page_turned', 'missed')),
  value      REAL    NOT NULL,                   -- lever angle [rad], page number, ...
  error_m    REAL                                -- NULL: not measured
);
CREATE TABLE IF NOT EXISTS ownership_changes(
  id         INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  unix_ns    INTEGER NOT NULL,
  object_id  TEXT    NOT NULL,
  owner      TEXT    NOT NULL,                   -- '' : free (the world server simulates it)
  reason     TEXT    NOT NULL
);
CREATE INDEX IF NOT EXISTS member_events_by_session ON member_events(session_id, unix_ns);
CREATE INDEX IF NOT EXISTS scene_changes_by_session ON scene_changes(session_id, unix_ns);
CREATE INDEX IF NOT EXISTS control_events_by_session ON control_events(session_id, control_id);
CREATE INDEX IF NOT EXISTS ownership_changes_by_session ON ownership_changes(session_id, unix_ns);
)sql";

// Version 2 on top of version 1 (a new file runs kCreateV1 then this; a version-1 file this).
// SQLite cannot change a CHECK in place: control_events is rebuilt with its rows.
inline constexpr const char* kMigrateV1ToV2 = R"sql(
CREATE TABLE control_events_v2(
  id         INTEGER PRIMARY KEY,
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  unix_ns    INTEGER NOT NULL,
  user       TEXT    NOT NULL,
  control_id TEXT    NOT NULL,
  kind       TEXT    NOT NULL CHECK (kind IN ('pressed', 'released', 'moved', 'page_turned', 'missed', 'opened')),
  value      REAL    NOT NULL,
  error_m    REAL
);
INSERT INTO control_events_v2(id, session_id, unix_ns, user, control_id, kind, value, error_m)
  SELECT id, session_id, unix_ns, user, control_id, kind, value, error_m FROM control_events;
DROP INDEX IF EXISTS control_events_by_session;
DROP TABLE control_events;
ALTER TABLE control_events_v2 RENAME TO control_events;
CREATE INDEX control_events_by_session ON control_events(session_id, control_id);
ALTER TABLE sessions ADD COLUMN resumed_from INTEGER REFERENCES sessions(id);
CREATE TABLE session_state(                      -- one row per session: where it is now
  session_id    INTEGER PRIMARY KEY REFERENCES sessions(id),
  unix_ns       INTEGER NOT NULL,
  scene         TEXT    NOT NULL,
  title         TEXT    NOT NULL,
  revision      INTEGER NOT NULL,                -- of the scene state last published
  gravity_x     REAL    NOT NULL,
  gravity_y     REAL    NOT NULL,
  gravity_z     REAL    NOT NULL,
  epoch_unix_ns INTEGER NOT NULL,                -- the session clock's origin
  message_id    INTEGER NOT NULL,                -- the board's last message, every language
  board_json    TEXT    NOT NULL                 -- [{"language", "text", "next_action"}, ...]
);
CREATE TABLE object_poses(                       -- the newest pose of each rigid body
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  object_id  TEXT    NOT NULL,
  unix_ns    INTEGER NOT NULL,
  owner      TEXT    NOT NULL,
  px REAL NOT NULL, py REAL NOT NULL, pz REAL NOT NULL,
  qw REAL NOT NULL, qx REAL NOT NULL, qy REAL NOT NULL, qz REAL NOT NULL,
  PRIMARY KEY(session_id, object_id)
);
PRAGMA user_version = 2;
)sql";

// Version 3 on top of version 2.
inline constexpr const char* kMigrateV2ToV3 = R"sql(
CREATE TABLE control_states(                     -- where each control of the current world settled
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  control_id TEXT    NOT NULL,
  unix_ns    INTEGER NOT NULL,
  scene      TEXT    NOT NULL,                   -- the world it belongs to
  idx        INTEGER NOT NULL,                   -- lever: detent; book: page (-1 shut); else -1
  engaged    INTEGER NOT NULL,                   -- button, arrow: pressed; book: open
  user       TEXT    NOT NULL,                   -- who changed it last ('' : nobody yet)
  changes    INTEGER NOT NULL,                   -- events that changed it
  PRIMARY KEY(session_id, control_id)
);
PRAGMA user_version = 3;
)sql";

// Version 4 on top of version 3.
inline constexpr const char* kMigrateV3ToV4 = R"sql(
CREATE TABLE visit_turns(                        -- a visitor's turn that ended (--visit-minutes)
  id              INTEGER PRIMARY KEY,
  session_id      INTEGER NOT NULL REFERENCES sessions(id),
  started_unix_ns INTEGER NOT NULL,              -- the member's join
  ended_unix_ns   INTEGER NOT NULL,
  member_id       TEXT    NOT NULL,
  user            TEXT    NOT NULL
);
CREATE TABLE visit_answers(                      -- the questionnaire at a turn's end, one score a row
  id           INTEGER PRIMARY KEY,
  session_id   INTEGER NOT NULL REFERENCES sessions(id),
  unix_ns      INTEGER NOT NULL,                 -- when the world server took them
  visitor      TEXT    NOT NULL,                 -- whose turn
  sent_by      TEXT    NOT NULL,                 -- the console's member name
  control_kind TEXT    NOT NULL CHECK (control_kind IN ('button', 'arrow', 'lever', 'book')),
  question     TEXT    NOT NULL CHECK (question IN ('ease', 'naturalness', 'satisfaction')),
  score        INTEGER NOT NULL CHECK (score BETWEEN 1 AND 7)
);
CREATE TABLE control_kinds(                      -- the kind of every control of the worlds shown
  session_id INTEGER NOT NULL REFERENCES sessions(id),
  control_id TEXT    NOT NULL,
  kind       TEXT    NOT NULL CHECK (kind IN ('button', 'arrow', 'lever', 'book')),
  PRIMARY KEY(session_id, control_id)
);
CREATE INDEX visit_answers_by_session ON visit_answers(session_id, visitor);
PRAGMA user_version = 4;
)sql";

// Version 5 on top of version 4.
inline constexpr const char* kMigrateV4ToV5 = R"sql(
CREATE TABLE loop_statistics(                    -- a station's loop statistics (1 Hz a node)
  id               INTEGER PRIMARY KEY,
  session_id       INTEGER NOT NULL REFERENCES sessions(id),
  unix_ns          INTEGER NOT NULL,             -- when the world server took the sample
  node             TEXT    NOT NULL,             -- haptic_node/USER, graphics_node/NAME, audio_guide/NAME
  rate_hz          REAL    NOT NULL,             -- loop passes (haptic steps, frames) a second
  jitter_p50_us    REAL    NOT NULL,
  jitter_p99_us    REAL    NOT NULL,
  jitter_max_us    REAL    NOT NULL,
  step_p50_us      REAL    NOT NULL,
  step_p99_us      REAL    NOT NULL,
  steps            INTEGER NOT NULL,             -- counts: since the node started
  overruns         INTEGER NOT NULL,
  resyncs          INTEGER NOT NULL,
  faults           INTEGER NOT NULL,
  samples_dropped  INTEGER NOT NULL,
  deadline_misses  INTEGER NOT NULL,
  sent_bytes_per_s REAL    NOT NULL              -- over the node's last statistics period
);
CREATE INDEX loop_statistics_by_session ON loop_statistics(session_id, node, unix_ns);
PRAGMA user_version = 5;
)sql";

// 0x48534C47 = "HSLG"; PRAGMAs take no parameters, so the numbers are spelled out.
inline constexpr const char* kStampV1 = "PRAGMA application_id = 1213418567; PRAGMA user_version = 1;";

inline constexpr const char* kInsertSession =
    "INSERT INTO sessions(name, domain_id, host, pid, schema_version, started_unix_ns, last_seen_unix_ns) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)";
inline constexpr const char* kInsertMember =
    "INSERT INTO member_events(session_id, unix_ns, change, member_id, user, kind, device, pid) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)";
inline constexpr const char* kInsertScene =
    "INSERT INTO scene_changes(session_id, unix_ns, scene, title) VALUES (?1, ?2, ?3, ?4)";
inline constexpr const char* kInsertControl =
    "INSERT INTO control_events(session_id, unix_ns, user, control_id, kind, value, error_m) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)";
inline constexpr const char* kInsertOwnership =
    "INSERT INTO ownership_changes(session_id, unix_ns, object_id, owner, reason) VALUES (?1, ?2, ?3, ?4, ?5)";
inline constexpr const char* kUpsertState =
    "INSERT OR REPLACE INTO session_state(session_id, unix_ns, scene, title, revision, gravity_x, gravity_y, "
    "gravity_z, epoch_unix_ns, message_id, board_json) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)";
inline constexpr const char* kUpsertPose =
    "INSERT OR REPLACE INTO object_poses(session_id, object_id, unix_ns, owner, px, py, pz, qw, qx, qy, qz) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)";
inline constexpr const char* kUpsertControlState =
    "INSERT OR REPLACE INTO control_states(session_id, control_id, unix_ns, scene, idx, engaged, user, changes) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8)";
inline constexpr const char* kInsertTurn =
    "INSERT INTO visit_turns(session_id, started_unix_ns, ended_unix_ns, member_id, user) VALUES (?1, ?2, ?3, ?4, ?5)";
inline constexpr const char* kInsertAnswer =
    "INSERT INTO visit_answers(session_id, unix_ns, visitor, sent_by, control_kind, question, score) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7)";
inline constexpr const char* kUpsertControlKind =
    "INSERT OR REPLACE INTO control_kinds(session_id, control_id, kind) VALUES (?1, ?2, ?3)";
inline constexpr const char* kInsertLoop =
    "INSERT INTO loop_statistics(session_id, unix_ns, node, rate_hz, jitter_p50_us, jitter_p99_us, jitter_max_us, "
    "step_p50_us, step_p99_us, steps, overruns, resyncs, faults, samples_dropped, deadline_misses, sent_bytes_per_s) "
    "VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11, ?12, ?13, ?14, ?15, ?16)";
inline constexpr const char* kUpdateResumedFrom = "UPDATE sessions SET resumed_from = ?1 WHERE id = ?2";
inline constexpr const char* kUpdateEnd = "UPDATE sessions SET ended_unix_ns = ?1 WHERE id = ?2";
inline constexpr const char* kUpdateSeen =
    "UPDATE sessions SET last_seen_unix_ns = ?1, dropped_rows = ?2 WHERE id = ?3";

}  // namespace handshare::server::schema
