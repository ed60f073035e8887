// The consumers of the session's events, each alone with a given event sequence: the session
// log writer (read back from a temporary SQLite file with plain sqlite3 calls), the pose trace
// and the console's lines (the wording the cross-process tests wait for).
#include <gtest/gtest.h>
#include <sqlite3.h>

#include <sstream>

#include "console_log.hpp"
#include "pose_trace.hpp"
#include "session_log_writer.hpp"
#include "test_support.hpp"

namespace handshare::server {
namespace {

using Clock = SessionEventSink::Clock;
using controls::EventKind;
using testing::kSecond;
using testing::kT0;
using testing::TempDir;

using testing::Query;  // one text value, read with sqlite3 alone ("<none>": no row)

BodyState Body(const std::string& id, const std::string& owner, double z) {
  BodyState b;
  b.object_id = id;
  b.owner = owner;
  b.X_WO.translation() = Eigen::Vector3d(0.1, 0.2, z);
  b.X_WO.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  b.v_WO_m_per_s = Eigen::Vector3d(0.0, 0.0, -0.5);
  return b;
}

ControlStateRecord Place(const std::string& id, std::int32_t index, bool known = true) {
  ControlStateRecord r;
  r.control_id = id;
  r.scene = "solar_system";
  r.index = index;
  r.user = "alice";
  r.changes = 2;
  r.known = known;
  return r;
}

SessionState State(std::uint32_t revision, std::uint32_t message_id) {
  SessionState st;
  st.scene = "solar_system";
  st.title = "Mars";
  st.revision = revision;
  st.gravity_W_m_per_s2[2] = -3.71;
  st.epoch_unix_ns = kT0;
  st.message_id = message_id;
  st.board = {{"en", "Now lift it on Mars.", "", ""}};
  return st;
}

// A world's controls' kinds (from its revision), a visitor's turn and her questionnaire go to the
// log as rows of their own; the answers are committed at once (their checkpoint).
TEST(SessionLogWriter, WritesTheControlsKindsATurnAndAQuestionnaire) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  const Member alice{"m-alice", "alice", "haptic", "sim", 42};
  const Clock::time_point t0 = Clock::now();
  SessionLog log(file, SessionStart{"s", 7, "h", 1, kT0});
  std::uint64_t clock = kT0;
  SessionLogWriter writer(log, [&clock] { return clock += kSecond; });
  scene::Scene world;
  world.controls = {testing::Control("lever", scene::ControlType::kLever),
                    testing::Control("book", scene::ControlType::kBook)};
  writer.Take(std::vector<SessionEvent>{SceneRevised{world, 1, kT0, 60.0}}, t0);
  controls::VisitAnswers answers;
  answers.visitor = "alice";
  answers.at(scene::ControlType::kBook, controls::VisitQuestion::kNaturalness) = 6;
  answers.at(scene::ControlType::kLever, controls::VisitQuestion::kEase) = 2;
  writer.Take(std::vector<SessionEvent>{TurnEnded{alice, std::chrono::seconds(3), 0.05, ""},
                                        VisitAnswered{"web-console", answers}, SessionCheckpoint{}},
              t0 + std::chrono::seconds(1));
  EXPECT_EQ(Query(file, "SELECT group_concat(control_id || ':' || kind, ',') FROM "
                        "(SELECT * FROM control_kinds ORDER BY control_id)"),
            "book:book,lever:lever");
  // The turn ended at the writer's clock (kT0 + 2 s) and began 3 s before.
  EXPECT_EQ(Query(file, "SELECT user || ':' || member_id || ':' || (ended_unix_ns - started_unix_ns) FROM visit_turns"),
            "alice:m-alice:3000000000");
  EXPECT_EQ(Query(file, "SELECT group_concat(visitor || ':' || sent_by || ':' || control_kind || ':' || question || ':' "
                        "|| score, ',') FROM (SELECT * FROM visit_answers ORDER BY id)"),
            "alice:web-console:lever:ease:2,alice:web-console:book:naturalness:6");
}

TEST(SessionLogWriter, WritesWhatAGivenEventSequenceSays) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  const Member alice{"m-alice", "alice", "haptic", "sim", 42};
  const Clock::time_point t0 = Clock::now();
  {
    SessionLog log(file, SessionStart{"s", 7, "h", 1, kT0});
    std::uint64_t clock = kT0;
    SessionLogWriter writer(log, [&clock] { return clock += kSecond; });
    const std::vector<SessionEvent> start{
        SceneRevised{scene::Scene{}, 1, kT0, 60.0}, SessionStateChanged{State(1, 0)},
        LineSaid{"not for the log"},
        SceneShown{"solar_system", "Moon"},
        WorldEntered{"solar_system"},
        ControlStateChanged{Place("lever", 0), true},
        MessageSaid{1, {{"en", "Hello", "", ""}}}, SessionStateChanged{State(1, 1)}};
    writer.Take(start, t0);
    const std::vector<SessionEvent> tick{
        MemberChanged{{MemberChange::kJoined, alice}, 1},
        ControlApplied{{kT0 + 5, "alice", "lever", EventKind::kMoved, 0.5, 0.004}},
        ControlStateChanged{Place("lever", 1), true},
        ControlStateChanged{Place("lever", 0), false},        // a hand moving it: not a place
        ControlStateChanged{Place("book", 2, false), true},   // unknown here: not the log's to say
        SessionStateChanged{State(2, 1)},
        OwnershipChanged{{"ball", "", "alice", OwnershipReason::kGranted}},
        BodyMoved{Body("ball", "alice", 0.25)},
        FieldChanged{"daphnia", DeformationSample{}},
        SessionCheckpoint{}};
    writer.Take(tick, t0 + std::chrono::milliseconds(17));
    // Committed by the checkpoint, not at the log's next period (200 ms).
    EXPECT_EQ(Query(file, "SELECT COUNT(*) FROM control_events"), "1");
    // 50 ms later the ball moved on: not logged (at most every 100 ms a body); 150 ms: logged.
    writer.Take(std::vector<SessionEvent>{BodyMoved{Body("ball", "alice", 0.30)}}, t0 + std::chrono::milliseconds(67));
    log.Flush();
    EXPECT_EQ(Query(file, "SELECT pz FROM object_poses"), "0.25");
    writer.Take(std::vector<SessionEvent>{BodyMoved{Body("ball", "alice", 0.35)}}, t0 + std::chrono::milliseconds(167));
    log.Flush();
  }
  EXPECT_EQ(Query(file, "SELECT change || ':' || member_id || ':' || user || ':' || kind || ':' || device || ':' || pid "
                        "FROM member_events"),
            "joined:m-alice:alice:haptic:sim:42");
  EXPECT_EQ(Query(file, "SELECT scene || ':' || title FROM scene_changes"), "solar_system:Moon");
  EXPECT_EQ(Query(file, "SELECT COUNT(*) FROM scene_changes"), "1");
  EXPECT_EQ(Query(file, "SELECT user || ':' || control_id || ':' || kind || ':' || value || ':' || error_m || ':' || "
                        "(unix_ns = " + std::to_string(kT0 + 5) + ") FROM control_events"),
            "alice:lever:moved:0.5:0.004:1");
  EXPECT_EQ(Query(file, "SELECT object_id || ':' || owner || ':' || reason FROM ownership_changes"), "ball:alice:granted");
  EXPECT_EQ(Query(file, "SELECT scene || ':' || title || ':' || revision || ':' || gravity_z || ':' || message_id || "
                        "':' || (epoch_unix_ns = " + std::to_string(kT0) + ") FROM session_state"),
            "solar_system:Mars:2:-3.71:1:1");
  EXPECT_NE(Query(file, "SELECT board_json FROM session_state").find("Now lift it on Mars."), std::string::npos);
  EXPECT_EQ(Query(file, "SELECT COUNT(*) FROM control_states"), "1");
  EXPECT_EQ(Query(file, "SELECT control_id || ':' || idx || ':' || user || ':' || changes FROM control_states"),
            "lever:1:alice:2");
  EXPECT_EQ(Query(file, "SELECT object_id || ':' || owner || ':' || px || ':' || pz FROM object_poses"),
            "ball:alice:0.1:0.35");
  const double qw = std::stod(Query(file, "SELECT qw FROM object_poses"));
  const double qz = std::stod(Query(file, "SELECT qz FROM object_poses"));
  EXPECT_NEAR(qw, std::cos(0.25), 1e-12);
  EXPECT_NEAR(qz, std::sin(0.25), 1e-12);
  // Every row stamped by the writer's clock, in the order taken: the scene row was its first.
  EXPECT_EQ(Query(file, "SELECT unix_ns = " + std::to_string(kT0 + 2 * kSecond) + " FROM scene_changes"), "1");
}

TEST(SessionLogWriter, AnotherWorldForgetsTheLastWorldsPosesAndPlaces) {
  TempDir dir;
  const auto file = dir / "log.sqlite";
  const Clock::time_point t0 = Clock::now();
  {
    SessionLog log(file, SessionStart{"s", 7, "h", 1, kT0});
    SessionLogWriter writer(log);
    writer.Take(std::vector<SessionEvent>{ControlStateChanged{Place("lever", 1), true},
                                          BodyMoved{Body("ball", "", 0.1)}, BodyMoved{Body("cube", "", 0.1)}},
                t0);
    // Another world within the pose period: its ball's first pose is logged all the same.
    writer.Take(std::vector<SessionEvent>{WorldEntered{"dinosaur"}, BodyMoved{Body("egg", "", 0.2)},
                                          BodyMoved{Body("ball", "", 0.3)}},
                t0 + std::chrono::milliseconds(10));
    log.Flush();
  }
  EXPECT_EQ(Query(file, "SELECT COUNT(*) FROM control_states"), "0");
  EXPECT_EQ(Query(file, "SELECT COUNT(*) FROM object_poses"), "2");  // the egg and the ball, not the cube
  EXPECT_EQ(Query(file, "SELECT COUNT(*) FROM object_poses WHERE object_id = 'cube'"), "0");
  EXPECT_EQ(Query(file, "SELECT pz FROM object_poses WHERE object_id = 'ball'"), "0.3");
}

TEST(PoseTrace, WritesAHeaderAndARowPerBodyStampedOncePerTick) {
  std::ostringstream out;
  std::uint64_t stamp = 1000;
  PoseTrace trace(out, [&stamp] { return stamp++; });
  trace.Take(std::vector<SessionEvent>{LineSaid{"x"}}, Clock::now());  // no body: no row
  trace.Take(std::vector<SessionEvent>{BodyMoved{Body("ball", "alice", 0.25)}, OwnershipChanged{},
                                       BodyMoved{Body("cube", "", 0.5)}},
             Clock::now());
  EXPECT_EQ(out.str(),
            "stamp_ns,object_id,owner,x_m,y_m,z_m,vx_m_per_s,vy_m_per_s,vz_m_per_s\n"
            "1000,ball,alice,0.1,0.2,0.25,0,0,-0.5\n"
            "1000,cube,,0.1,0.2,0.5,0,0,-0.5\n");
}

TEST(ConsoleLog, SaysTheLinesTheOperatorAndTheTestsReadInTheTicksOrder) {
  std::vector<std::string> lines;
  ConsoleLog console([&lines](const std::string& line) { lines.push_back(line); });
  const Member alice{"m-alice", "alice", "haptic", "sim", 42};
  const Member screen{"m-screen", "screen", "graphics", "", 7};
  console.Take(
      std::vector<SessionEvent>{
          LineSaid{"session 's' on domain 7: scene 'start_menu' (3 objects)"},
          MemberChanged{{MemberChange::kJoined, alice}, 1},
          MemberChanged{{MemberChange::kLost, screen}, 0},
          RosterChanged{{"m-alice"}},
          ControlApplied{{kT0, "alice", "lever", EventKind::kMoved, 0.5, 0.004}},
          ControlApplied{{kT0, "alice", "button", EventKind::kMissed, 0.0, std::nullopt}},
          SceneShown{"solar_system", "Moon"},
          OwnershipChanged{{"ball", "", "alice", OwnershipReason::kGranted}},
          MessageSaid{4, {{"ja", "月へようこそ", "", ""}, {"en", "Welcome to the Moon", "", ""}}},
          BodyMoved{Body("ball", "alice", 0.25)},
          SessionCheckpoint{},
      },
      Clock::now());
  EXPECT_EQ(lines, (std::vector<std::string>{
                       "session 's' on domain 7: scene 'start_menu' (3 objects)",
                       "member joined: user=alice kind=haptic device=sim pid=42 present=1",
                       "member lost: user=screen kind=graphics pid=7 present=0",
                       "control lever: moved by alice (value 0.500, error 4.000 mm)",
                       "control button: missed by alice (value 0.000, error -)",
                       "scene 'solar_system': Moon",
                       "object 'ball': owner '' -> 'alice' (granted)",
                       "message board #4: Welcome to the Moon",
                   }));
}

}  // namespace
}  // namespace handshare::server
