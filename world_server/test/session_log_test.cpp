#include "handshare/world_server/session_log.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <fstream>
#include <functional>
#include <thread>
#include <vector>

#include "test_support.hpp"

namespace handshare::server {
namespace {

using testing::ErrorOf;
using testing::kSecond;
using testing::kT0;
using testing::TempDir;

// An independent reader: plain sqlite3 calls, none of the library's helpers.
class RawDb {
 public:
  explicit RawDb(const std::filesystem::path& file, int flags = SQLITE_OPEN_READWRITE) {
    if (sqlite3_open_v2(file.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
      ADD_FAILURE() << "cannot open " << file << ": " << sqlite3_errmsg(db_);
    }
  }
  ~RawDb() { sqlite3_close(db_); }
  std::string Text(const std::string& sql) {
    sqlite3_stmt* s = nullptr;
    std::string out = "<error>";
    if (sqlite3_prepare_v2(db_, sql.c_str(), -1, &s, nullptr) == SQLITE_OK && sqlite3_step(s) == SQLITE_ROW) {
      const auto* t = sqlite3_column_text(s, 0);
      out = t ? reinterpret_cast<const char*>(t) : "<null>";
    } else {
      ADD_FAILURE() << sql << ": " << sqlite3_errmsg(db_);
    }
    sqlite3_finalize(s);
    return out;
  }
  std::int64_t Int(const std::string& sql) { return std::stoll(Text(sql)); }
  void Exec(const std::string& sql) {
    char* error = nullptr;
    if (sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
      ADD_FAILURE() << sql << ": " << (error ? error : "?");
    }
    sqlite3_free(error);
  }

 private:
  sqlite3* db_ = nullptr;
};

SessionStart Start(const std::string& name, std::uint64_t unix_ns = 1'700'000'000'000'000'000ULL) {
  return SessionStart{name, 120, "testhost", 4242, unix_ns};
}

TEST(SessionLog, CreatesAVersionedWalLogAndRecordsEveryKindOfRow) {
  TempDir dir;
  const auto file = dir / "session.sqlite";
  {
    SessionLog log(file, Start("demo"));
    EXPECT_EQ(log.session_id(), 1);
    log.OnSceneChange("start_menu", "Start menu", kT0);
    log.OnMember(MemberChange::kJoined, Member{"demo/alice", "alice", "haptic", "sim", 11}, kT0 + 1 * kSecond);
    log.OnControlEvent(ControlRecord{kT0 + 2 * kSecond, "alice", "lever", controls::EventKind::kMoved, 0.5, 0.004});
    log.OnControlEvent(ControlRecord{kT0 + 3 * kSecond, "alice", "lever", controls::EventKind::kMissed, 0.0, std::nullopt});
    // A hand's motion report is no event of the session (the recorder passes every control
    // event it hears: one made the log refuse its row and the recorder stop).
    log.OnControlEvent(ControlRecord{kT0 + 3 * kSecond, "alice", "lever", controls::EventKind::kMoving, 0.3, std::nullopt});
    log.OnOwnership("ball", "alice", "granted", kT0 + 4 * kSecond);
    log.OnMember(MemberChange::kLost, Member{"demo/alice", "alice", "haptic", "sim", 11}, kT0 + 5 * kSecond);
    log.Flush();
    EXPECT_EQ(log.error(), "");

    // Readable by another connection while the server still runs (WAL).
    RawDb raw(file, SQLITE_OPEN_READONLY);
    EXPECT_EQ(raw.Int("PRAGMA user_version"), SessionLog::kSchemaVersion);
    EXPECT_EQ(raw.Int("PRAGMA application_id"), SessionLog::kApplicationId);
    EXPECT_EQ(raw.Text("PRAGMA journal_mode"), "wal");
    EXPECT_EQ(raw.Text("SELECT name || '|' || domain_id || '|' || host || '|' || pid FROM sessions"),
              "demo|120|testhost|4242");
    EXPECT_EQ(raw.Text("SELECT count(*) FROM sessions WHERE ended_unix_ns IS NULL"), "1");
    EXPECT_EQ(raw.Text("SELECT scene || '|' || title FROM scene_changes"), "start_menu|Start menu");
    EXPECT_EQ(raw.Text("SELECT group_concat(change || ':' || user || ':' || kind || ':' || device, ',') "
                       "FROM (SELECT * FROM member_events ORDER BY id)"),
              "joined:alice:haptic:sim,lost:alice:haptic:sim");
    EXPECT_EQ(raw.Text("SELECT group_concat(kind || ':' || value || ':' || ifnull(error_m, 'null'), ',') "
                       "FROM (SELECT * FROM control_events ORDER BY id)"),
              "moved:0.5:0.004,missed:0.0:null");
    EXPECT_EQ(raw.Text("SELECT object_id || ':' || owner || ':' || reason FROM ownership_changes"), "ball:alice:granted");
    EXPECT_EQ(raw.Int("SELECT unix_ns FROM member_events WHERE change = 'lost'"),
              static_cast<std::int64_t>(kT0 + 5 * kSecond));
  }
  // Destruction ends the session.
  RawDb raw(file, SQLITE_OPEN_READONLY);
  EXPECT_EQ(raw.Text("SELECT count(*) FROM sessions WHERE ended_unix_ns IS NOT NULL"), "1");
}

// A log whose server ended is one file (no -wal, -shm left for a read-only reader to trip
// over), and the next server switches it back to WAL.
TEST(SessionLog, AFinishedLogIsOneFileAndWalAgainWhenReopened) {
  TempDir dir;
  const auto file = dir / "session.db";
  const auto wal = dir / "session.db-wal", shm = dir / "session.db-shm";
  {
    SessionLog log(file, Start("one"));
    log.OnSceneChange("start_menu", "Start", kT0);
    log.Flush();
    EXPECT_TRUE(std::filesystem::exists(wal));
  }
  EXPECT_FALSE(std::filesystem::exists(wal));
  EXPECT_FALSE(std::filesystem::exists(shm));
  {
    RawDb raw(file, SQLITE_OPEN_READONLY);
    EXPECT_EQ(raw.Text("PRAGMA journal_mode"), "delete");
    EXPECT_EQ(raw.Text("SELECT scene FROM scene_changes"), "start_menu");
  }
  EXPECT_FALSE(std::filesystem::exists(shm));  // a read-only reader of a finished log leaves nothing
  {
    SessionLog second(file, Start("two", kT0 + 100 * kSecond));
    RawDb raw(file, SQLITE_OPEN_READONLY);  // open while the server ends: the mode stays WAL
    EXPECT_EQ(raw.Text("PRAGMA journal_mode"), "wal");
    second.OnSceneChange("dinosaur", "Dinosaur", kT0 + 101 * kSecond);
  }
  RawDb raw(file, SQLITE_OPEN_READONLY);
  EXPECT_EQ(raw.Text("SELECT group_concat(scene, ',') FROM (SELECT scene FROM scene_changes ORDER BY id)"),
            "start_menu,dinosaur");
}

TEST(SessionLog, ReopeningAppendsANewSession) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  {
    SessionLog first(file, Start("one"));
    first.OnSceneChange("start_menu", "Start", kT0);
    first.End(kT0 + 10 * kSecond);
    first.End(kT0 + 20 * kSecond);  // only the first end counts
  }
  {
    SessionLog second(file, Start("two", kT0 + 100 * kSecond));
    EXPECT_EQ(second.session_id(), 2);
    second.OnSceneChange("solar_system", "Solar system", kT0 + 101 * kSecond);
  }
  RawDb raw(file, SQLITE_OPEN_READONLY);
  EXPECT_EQ(raw.Text("SELECT group_concat(id || ':' || name, ',') FROM sessions"), "1:one,2:two");
  EXPECT_EQ(raw.Int("SELECT ended_unix_ns FROM sessions WHERE id = 1"), static_cast<std::int64_t>(kT0 + 10 * kSecond));
  EXPECT_EQ(raw.Text("SELECT group_concat(session_id || ':' || scene, ',') FROM scene_changes"),
            "1:start_menu,2:solar_system");
}

TEST(SessionLog, RowsFromManyThreadsAllArrive) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  constexpr int kThreads = 4, kEach = 2500;
  {
    SessionLog log(file, Start("busy"));
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t) {
      threads.emplace_back([&log, t] {
        for (int i = 0; i < kEach; ++i) {
          log.OnControlEvent(ControlRecord{kT0 + static_cast<std::uint64_t>(i), "user" + std::to_string(t), "button",
                                           controls::EventKind::kPressed, 1.0, 0.001 * i});
        }
      });
    }
    for (auto& th : threads) th.join();
    log.Flush();
    EXPECT_EQ(log.dropped_rows(), 0u);
  }
  RawDb raw(file, SQLITE_OPEN_READONLY);
  EXPECT_EQ(raw.Int("SELECT count(*) FROM control_events"), kThreads * kEach);
  EXPECT_EQ(raw.Int("SELECT count(DISTINCT user) FROM control_events"), kThreads);
}

TEST(SessionLog, AFullQueueDropsAndCountsRows) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  SessionLogConfig config;
  config.flush_period = std::chrono::hours(1);  // the writer only wakes on Flush and at the end
  config.max_queued_rows = 10;
  {
    SessionLog log(file, Start("slow"), config);
    for (int i = 0; i < 15; ++i) log.OnSceneChange("s" + std::to_string(i), "", kT0);
    EXPECT_EQ(log.dropped_rows(), 5u);
    log.Flush();
  }
  RawDb raw(file, SQLITE_OPEN_READONLY);
  EXPECT_EQ(raw.Int("SELECT count(*) FROM scene_changes"), 10);
  EXPECT_EQ(raw.Int("SELECT dropped_rows FROM sessions"), 5);
  EXPECT_EQ(raw.Int("SELECT count(*) FROM sessions WHERE ended_unix_ns IS NOT NULL"), 1);  // queued after Flush
}

TEST(SessionLog, AWriteErrorIsKeptAndThrownByFlush) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  SessionLogConfig config;
  config.busy_timeout = std::chrono::milliseconds(50);
  SessionLog log(file, Start("locked"), config);
  RawDb other(file);
  other.Exec("BEGIN EXCLUSIVE");  // another writer holds the lock longer than the busy timeout
  log.OnSceneChange("start_menu", "", kT0);
  const std::string error = ErrorOf([&] { log.Flush(); });
  other.Exec("ROLLBACK");
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_NE(error.find("starting a write transaction"), std::string::npos) << error;
  EXPECT_NE(error.find("locked"), std::string::npos) << error;
  EXPECT_EQ(log.error(), error);
  log.OnSceneChange("ignored", "", kT0);  // after an error, rows are refused quietly
  EXPECT_THROW(log.Flush(), SessionLogError);
}

TEST(SessionLog, ATextFileIsNotADatabase) {
  TempDir dir;
  const auto file = dir / "notes.txt";
  std::ofstream(file) << "these are not the droids you are looking for, nor a SQLite file\n";
  const std::string error = ErrorOf([&] { SessionLog log(file, Start("x")); });
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_NE(error.find("not a database"), std::string::npos) << error;
}

TEST(SessionLog, AnotherApplicationsDatabaseIsRefusedAndLeftAlone) {
  TempDir dir;
  const auto file = dir / "other.sqlite";
  {
    RawDb raw(file, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
    raw.Exec("CREATE TABLE recipes(name TEXT)");
  }
  const std::string error = ErrorOf([&] { SessionLog log(file, Start("x")); });
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_NE(error.find("not a handshare session log"), std::string::npos) << error;
  RawDb raw(file, SQLITE_OPEN_READONLY);
  EXPECT_EQ(raw.Text("PRAGMA journal_mode"), "delete");  // not switched to WAL
  EXPECT_EQ(raw.Int("SELECT count(*) FROM sqlite_master"), 1);
}

TEST(SessionLog, ANewerSchemaIsRefused) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  { SessionLog log(file, Start("old")); }
  {
    RawDb raw(file);
    raw.Exec("PRAGMA user_version = 7");
  }
  const std::string error = ErrorOf([&] { SessionLog log(file, Start("x")); });
  EXPECT_NE(error.find("schema version 7 is newer"), std::string::npos) << error;
}

TEST(SessionLog, AFolderThatDoesNotExistOrIsReadOnlyIsNamed) {
  TempDir dir;
  const auto missing = dir / "no_such_folder" / "log.sqlite";
  std::string error = ErrorOf([&] { SessionLog log(missing, Start("x")); });
  EXPECT_NE(error.find(missing.string()), std::string::npos) << error;
  EXPECT_NE(error.find("unable to open database file"), std::string::npos) << error;

  if (geteuid() == 0) GTEST_SKIP() << "root ignores directory permissions";
  const auto locked_dir = dir / "locked";
  std::filesystem::create_directory(locked_dir);
  std::filesystem::permissions(locked_dir, std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
  const auto file = locked_dir / "log.sqlite";
  error = ErrorOf([&] { SessionLog log(file, Start("x")); });
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_NE(error.find("cannot open or create"), std::string::npos) << error;
}

TEST(SessionLog, AReadOnlyFileIsNamed) {
  if (geteuid() == 0) GTEST_SKIP() << "root ignores file permissions";
  TempDir dir;
  const auto file = dir / "log.sqlite";
  { SessionLog log(file, Start("first")); }
  std::filesystem::permissions(file, std::filesystem::perms::owner_read);
  const std::string error = ErrorOf([&] { SessionLog log(file, Start("x")); });
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
  EXPECT_NE(error.find("read-only"), std::string::npos) << error;
}

TEST(ControlEventLogNames, RoundTripEveryKindAndCountAnOpenedBookAsAHit) {
  using controls::EventKind;
  for (EventKind k : {EventKind::kPressed, EventKind::kReleased, EventKind::kMoved, EventKind::kPageTurned,
                      EventKind::kMissed, EventKind::kOpened}) {
    EXPECT_EQ(EventKindFromLogName(LogName(k)), k);
  }
  EXPECT_STREQ(LogName(EventKind::kOpened), "opened");  // not "pressed", as it once was logged
  EXPECT_FALSE(EventKindFromLogName("kicked"));
  EXPECT_TRUE(IsHit(EventKind::kPageTurned));
  EXPECT_TRUE(IsHit(EventKind::kOpened));
  EXPECT_FALSE(IsHit(EventKind::kMissed));
  EXPECT_FALSE(IsHit(EventKind::kReleased));
}

}  // namespace
}  // namespace handshare::server
