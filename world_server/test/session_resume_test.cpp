// Where a session is, in its log: the state and body poses a restarted server resumes from,
// and the migration that gives an old (version 1) log the tables for it.
#include <gtest/gtest.h>
#include <sqlite3.h>

#include "handshare/world_server/session_log.hpp"
#include "session_schema.hpp"
#include "test_support.hpp"

namespace handshare::server {
namespace {

using testing::kSecond;
using testing::kT0;
using testing::TempDir;

using testing::QueryInt;

void Exec(const std::filesystem::path& file, const std::string& sql) {
  sqlite3* db = nullptr;
  sqlite3_open_v2(file.c_str(), &db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, nullptr);
  char* error = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) ADD_FAILURE() << sql << ": " << error;
  sqlite3_free(error);
  sqlite3_close(db);
}

SessionState MarsState() {
  SessionState st;
  st.unix_ns = kT0 + 5 * kSecond;
  st.scene = "solar_system";
  st.title = "Mars";
  st.revision = 3;
  st.gravity_W_m_per_s2[2] = -3.71;
  st.epoch_unix_ns = kT0;
  st.message_id = 4;
  st.board = {{"en", "Now lift it on Mars.", "Pull the lever back.", ""}, {"ja", "火星で持ち上げよう。", "", "かせいで もちあげよう。"}};
  return st;
}

// A server that was killed: its session never ended (the log's destructor ends it, so the
// test takes that back, as a kill -9 would have left it).
void KilledSession(const std::filesystem::path& file, const std::string& name, std::uint64_t last_seen) {
  std::int64_t id = 0;
  {
    SessionLog log(file, SessionStart{name, 5, "h", 1, kT0});
    log.OnState(MarsState());
    ObjectPose ball;
    ball.object_id = "ball";
    ball.owner = "alice";
    ball.p_WO_m[2] = 0.25;
    log.OnObjectPose(ball);
    log.Flush();
    id = log.session_id();
  }
  Exec(file, "UPDATE sessions SET ended_unix_ns = NULL, last_seen_unix_ns = " + std::to_string(last_seen) +
                 " WHERE id = " + std::to_string(id));
}

TEST(SessionResume, AKilledServersSessionIsFoundWithItsStateAndPoses) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  KilledSession(file, "museum", kT0 + 6 * kSecond);
  const auto r = FindResumePoint(file, "museum", kT0 + 8 * kSecond, 600 * kSecond);
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->last_seen_unix_ns, kT0 + 6 * kSecond);
  EXPECT_EQ(r->state.scene, "solar_system");
  EXPECT_EQ(r->state.title, "Mars");
  EXPECT_EQ(r->state.revision, 3u);
  EXPECT_EQ(r->state.gravity_W_m_per_s2[2], -3.71);
  EXPECT_EQ(r->state.epoch_unix_ns, kT0);
  EXPECT_EQ(r->state.message_id, 4u);
  ASSERT_EQ(r->state.board.size(), 2u);
  EXPECT_EQ(r->state.board[0].next_action, "Pull the lever back.");
  EXPECT_EQ(r->state.board[1].text, "火星で持ち上げよう。");
  EXPECT_EQ(r->state.board[1].reading, "かせいで もちあげよう。");
  ASSERT_EQ(r->poses.size(), 1u);
  EXPECT_EQ(r->poses[0].object_id, "ball");
  EXPECT_EQ(r->poses[0].owner, "alice");
  EXPECT_EQ(r->poses[0].p_WO_m[2], 0.25);
  // Another session's name, or a server killed too long ago: start afresh.
  EXPECT_FALSE(FindResumePoint(file, "lab", kT0 + 8 * kSecond, 600 * kSecond).has_value());
  EXPECT_FALSE(FindResumePoint(file, "museum", kT0 + 700 * kSecond, 600 * kSecond).has_value());
  // No log yet: nothing to resume.
  EXPECT_FALSE(FindResumePoint(dir / "none.sqlite", "museum", kT0, 600 * kSecond).has_value());
}

TEST(SessionResume, ACleanlyEndedOrAlreadyResumedSessionIsNotResumed) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  {
    SessionLog log(file, SessionStart{"museum", 5, "h", 1, kT0});
    log.OnState(MarsState());
  }  // ended cleanly
  EXPECT_FALSE(FindResumePoint(file, "museum", kT0 + kSecond, 600 * kSecond).has_value());
  KilledSession(file, "museum", kT0 + 6 * kSecond);
  const auto r = FindResumePoint(file, "museum", kT0 + 7 * kSecond, 600 * kSecond);
  ASSERT_TRUE(r.has_value());
  // The resuming server's own session names it, and from then on is the newest.
  std::int64_t resumed = 0;
  {
    SessionLog log(file, SessionStart{"museum", 5, "h", 2, kT0 + 7 * kSecond, r->session_id});
    resumed = log.session_id();
  }
  EXPECT_EQ(QueryInt(file, "SELECT resumed_from FROM sessions WHERE id = " + std::to_string(resumed)), r->session_id);
  EXPECT_FALSE(FindResumePoint(file, "museum", kT0 + 8 * kSecond, 600 * kSecond).has_value());
}

TEST(SessionResume, AnotherWorldForgetsTheLastWorldsPoses) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  {
    SessionLog log(file, SessionStart{"museum", 5, "h", 1, kT0});
    ObjectPose ball;
    ball.object_id = "ball";
    log.OnObjectPose(ball);
    log.ForgetObjectPoses();
    log.OnState(MarsState());
    log.Flush();
    EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM object_poses"), 0);
  }
}

ControlPlace Place(const std::string& id, std::int32_t index, bool engaged, const std::string& user,
                   std::uint32_t changes) {
  ControlPlace p;
  p.control_id = id;
  p.scene = "solar_system";
  p.unix_ns = kT0 + 4 * kSecond;
  p.index = index;
  p.engaged = engaged;
  p.user = user;
  p.changes = changes;
  return p;
}

// Where the controls settled comes back with the session: the lever in Mars' detent, a book
// open at its page, a button at rest that nobody touched (every control of the world has a
// place from the moment the world appears). A control's newest place replaces the last.
TEST(SessionResume, WhereTheControlsSettledIsResumed) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  std::int64_t id = 0;
  {
    SessionLog log(file, SessionStart{"museum", 5, "h", 1, kT0});
    log.OnState(MarsState());
    log.OnControlPlace(Place("lever_planet", 0, false, "", 0));
    log.OnControlPlace(Place("book_solar_system", -1, false, "", 0));
    log.OnControlPlace(Place("button_reset", -1, false, "", 0));
    log.OnControlPlace(Place("lever_planet", 1, false, "alice", 1));
    log.OnControlPlace(Place("book_solar_system", 2, true, "bob", 3));
    log.Flush();
    id = log.session_id();
  }
  Exec(file, "UPDATE sessions SET ended_unix_ns = NULL, last_seen_unix_ns = " + std::to_string(kT0 + 6 * kSecond) +
                 " WHERE id = " + std::to_string(id));
  const auto r = FindResumePoint(file, "museum", kT0 + 7 * kSecond, 600 * kSecond);
  ASSERT_TRUE(r.has_value());
  ASSERT_EQ(r->controls.size(), 3u);  // by id
  EXPECT_EQ(r->controls[0].control_id, "book_solar_system");
  EXPECT_EQ(r->controls[0].index, 2);
  EXPECT_TRUE(r->controls[0].engaged);
  EXPECT_EQ(r->controls[0].user, "bob");
  EXPECT_EQ(r->controls[0].changes, 3u);
  EXPECT_EQ(r->controls[1].control_id, "button_reset");
  EXPECT_EQ(r->controls[1].index, -1);
  EXPECT_FALSE(r->controls[1].engaged);
  EXPECT_EQ(r->controls[1].user, "");
  EXPECT_EQ(r->controls[2].control_id, "lever_planet");
  EXPECT_EQ(r->controls[2].scene, "solar_system");
  EXPECT_EQ(r->controls[2].index, 1);
  EXPECT_EQ(r->controls[2].user, "alice");
  EXPECT_EQ(r->controls[2].changes, 1u);
}

TEST(SessionResume, AnotherWorldForgetsTheLastWorldsControls) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  SessionLog log(file, SessionStart{"museum", 5, "h", 1, kT0});
  log.OnControlPlace(Place("lever_planet", 1, false, "alice", 1));
  log.ForgetControlPlaces();
  log.OnControlPlace(Place("arrow_next", -1, false, "", 0));
  log.Flush();
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM control_states"), 1);
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM control_states WHERE control_id = 'arrow_next'"), 1);
}

// A log a version-2 server wrote (no control places) is migrated with its rows, and its
// killed session resumes with no places: the resumed server leaves those controls unknown,
// as before.
TEST(SessionResume, AVersionTwoLogIsMigratedAndResumesWithoutPlaces) {
  TempDir dir;
  const auto file = dir / "v2.sqlite";
  Exec(file, std::string("PRAGMA journal_mode=WAL;") + schema::kCreateV1 + schema::kStampV1 + schema::kMigrateV1ToV2);
  Exec(file,
       "INSERT INTO sessions(id, name, domain_id, host, pid, schema_version, started_unix_ns, last_seen_unix_ns) "
       "VALUES (1, 'museum', 5, 'h', 1, 2, " + std::to_string(kT0) + ", " + std::to_string(kT0 + 6 * kSecond) + ");"
       "INSERT INTO session_state(session_id, unix_ns, scene, title, revision, gravity_x, gravity_y, gravity_z, "
       "epoch_unix_ns, message_id, board_json) VALUES (1, " + std::to_string(kT0 + 5 * kSecond) +
       ", 'solar_system', 'Mars', 3, 0, 0, -3.71, " + std::to_string(kT0) + ", 4, '[]');");
  EXPECT_EQ(QueryInt(file, "PRAGMA user_version"), 2);
  const auto before = FindResumePoint(file, "museum", kT0 + 7 * kSecond, 600 * kSecond);
  ASSERT_TRUE(before.has_value());  // read as it is, no places
  EXPECT_TRUE(before->controls.empty());
  {
    SessionLog log(file, SessionStart{"museum", 5, "h", 2, kT0 + 7 * kSecond, before->session_id});
    log.OnControlPlace(Place("lever_planet", 1, false, "alice", 1));
    log.Flush();
    EXPECT_TRUE(log.error().empty()) << log.error();
  }
  EXPECT_EQ(QueryInt(file, "PRAGMA user_version"), SessionLog::kSchemaVersion);
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM session_state WHERE session_id = 1"), 1);
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM control_states WHERE session_id = 2"), 1);
}

TEST(SessionResume, AVersionOneLogIsMigratedWithEveryRowAndThenTakesOpenedBooks) {
  TempDir dir;
  const auto file = dir / "old.sqlite";
  Exec(file, std::string("PRAGMA journal_mode=WAL;") + schema::kCreateV1 + schema::kStampV1);
  Exec(file,
       "INSERT INTO sessions(id, name, domain_id, host, pid, schema_version, started_unix_ns, last_seen_unix_ns) "
       "VALUES (1, 'old', 5, 'h', 1, 1, 10, 20);"
       "INSERT INTO control_events(session_id, unix_ns, user, control_id, kind, value, error_m) "
       "VALUES (1, 15, 'alice', 'lever', 'moved', 0.5, 0.002);");
  // Version 1 refuses a book's opening: the reason for version 2.
  sqlite3* raw = nullptr;
  sqlite3_open_v2(file.c_str(), &raw, SQLITE_OPEN_READWRITE, nullptr);
  EXPECT_NE(sqlite3_exec(raw,
                         "INSERT INTO control_events(session_id, unix_ns, user, control_id, kind, value) "
                         "VALUES (1, 16, 'alice', 'book', 'opened', 0)",
                         nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(raw);
  {
    SessionLog log(file, SessionStart{"new", 5, "h", 2, kT0});
    ControlRecord opened;
    opened.unix_ns = kT0 + kSecond;
    opened.user = "bob";
    opened.control_id = "book_dinosaur";
    opened.kind = controls::EventKind::kOpened;
    log.OnControlEvent(opened);
    log.OnState(MarsState());
    log.Flush();
    EXPECT_TRUE(log.error().empty()) << log.error();
  }
  EXPECT_EQ(QueryInt(file, "PRAGMA user_version"), SessionLog::kSchemaVersion);
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM control_events WHERE kind = 'moved' AND session_id = 1"), 1);
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM control_events WHERE kind = 'opened'"), 1);
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM session_state"), 1);
  EXPECT_EQ(QueryInt(file, "SELECT count(*) FROM sessions"), 2);
}

}  // namespace
}  // namespace handshare::server
