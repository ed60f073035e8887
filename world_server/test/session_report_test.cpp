#include "handshare/world_server/session_report.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <sstream>

#include "test_support.hpp"

namespace handshare::server {
namespace {

using testing::ErrorOf;
using testing::kSecond;
using testing::kT0;
using testing::TempDir;

TEST(Summarize, SampleMeanAndStandardDeviation) {
  EXPECT_EQ(Summarize({}).n, 0u);
  const Summary one = Summarize({2.5});
  EXPECT_EQ(one.n, 1u);
  EXPECT_DOUBLE_EQ(one.mean, 2.5);
  EXPECT_DOUBLE_EQ(one.sd, 0.0);
  // 1, 2, 3, 4: mean 2.5, squared deviations 2.25 + 0.25 + 0.25 + 2.25 = 5, sd = sqrt(5 / 3).
  const Summary four = Summarize({1.0, 2.0, 3.0, 4.0});
  EXPECT_DOUBLE_EQ(four.mean, 2.5);
  EXPECT_NEAR(four.sd, std::sqrt(5.0 / 3.0), 1e-15);
  // A large offset does not cancel the spread (two-pass): 1e9 + {1, 2, 3, 4}.
  const Summary offset = Summarize({1e9 + 1, 1e9 + 2, 1e9 + 3, 1e9 + 4});
  EXPECT_NEAR(offset.sd, std::sqrt(5.0 / 3.0), 1e-6);
}

// The paper's Table 4 gives, per control, the number of subjects (5) and the mean and standard
// deviation of their misses: arrow 1.40 / 1.52, book 0.60 / 0.89, button 0.40 / 0.89, lever
// 3.60 / 1.14. The paper lists no per-subject numbers; these miss counts are one set that gives
// exactly those summaries (checked by hand: e.g. lever 2,3,4,4,5 -> mean 3.6, sd sqrt(5.2/4)).
TEST(ComputeControlStats, ReproducesThePapersTable4FromPerUserMisses) {
  const std::map<std::string, std::vector<int>> misses = {
      {"arrow", {0, 0, 1, 3, 3}}, {"book", {0, 0, 0, 1, 2}}, {"button", {0, 0, 0, 0, 2}}, {"lever", {2, 3, 4, 4, 5}}};
  std::vector<ControlRecord> events;
  std::uint64_t t = kT0;
  for (const auto& [control, per_user] : misses) {
    for (std::size_t u = 0; u < per_user.size(); ++u) {
      const std::string user = "subject" + std::to_string(u + 1);
      for (int m = 0; m < per_user[u]; ++m) events.push_back({t++, user, control, controls::EventKind::kMissed, 0.0, 0.02});
      // "they had to hit each control more than 10 times"
      for (int h = 0; h < 11; ++h) {
        events.push_back({t++, user, control, controls::EventKind::kPressed, 1.0, 0.002});
        events.push_back({t++, user, control, controls::EventKind::kReleased, 0.0, std::nullopt});
      }
    }
  }
  const auto stats = ComputeControlStats(events);
  ASSERT_EQ(stats.size(), 4u);
  struct Row {
    const char* id;
    double mean, sd;
    std::size_t misses;
  };
  const Row table4[] = {{"arrow", 1.40, 1.52, 7}, {"book", 0.60, 0.89, 3}, {"button", 0.40, 0.89, 2}, {"lever", 3.60, 1.14, 18}};
  for (std::size_t i = 0; i < 4; ++i) {
    SCOPED_TRACE(table4[i].id);
    EXPECT_EQ(stats[i].control_id, table4[i].id);
    EXPECT_EQ(stats[i].misses_per_user.n, 5u);
    EXPECT_NEAR(stats[i].misses_per_user.mean, table4[i].mean, 0.005);  // the table rounds to 2 decimals
    EXPECT_NEAR(stats[i].misses_per_user.sd, table4[i].sd, 0.005);
    EXPECT_EQ(stats[i].hits, 55u);
    EXPECT_EQ(stats[i].released, 55u);
    EXPECT_EQ(stats[i].misses, table4[i].misses);
    EXPECT_EQ(stats[i].error_m.n, 55u);  // hits only: misses and releases are not hit errors
    EXPECT_NEAR(stats[i].error_m.mean, 0.002, 1e-15);
  }
}

TEST(ComputeControlStats, ErrorsOfHitsAndUsersWhoNeverMissed) {
  const std::vector<ControlRecord> events = {
      {kT0, "alice", "lever", controls::EventKind::kMoved, 0.3, 0.001},
      {kT0, "alice", "lever", controls::EventKind::kMoved, 0.3, 0.002},
      {kT0, "bob", "lever", controls::EventKind::kMissed, 0.0, 0.003},
      {kT0, "bob", "lever", controls::EventKind::kPageTurned, 0.0, 0.004},
      {kT0, "bob", "lever", controls::EventKind::kPressed, 0.0, std::nullopt},  // no error measured
      {kT0, "carol", "book", controls::EventKind::kPageTurned, 3.0, std::nullopt},
  };
  const auto stats = ComputeControlStats(events);
  ASSERT_EQ(stats.size(), 2u);
  const ControlStats& book = stats[0];
  EXPECT_EQ(book.control_id, "book");
  EXPECT_EQ(book.hits, 1u);
  EXPECT_EQ(book.error_m.n, 0u);
  const ControlStats& lever = stats[1];
  EXPECT_EQ(lever.hits, 4u);
  EXPECT_EQ(lever.misses, 1u);
  // Hits 1, 2 and 4 mm (the miss at 3 mm is not a hit error): mean 7/3 mm, squared deviations
  // (16 + 1 + 25) / 9 mm^2 over n - 1 = 2: sd = sqrt(7/3) mm.
  EXPECT_EQ(lever.error_m.n, 3u);
  EXPECT_NEAR(lever.error_m.mean, 0.007 / 3.0, 1e-15);
  EXPECT_NEAR(lever.error_m.sd, 0.001 * std::sqrt(7.0 / 3.0), 1e-15);
  EXPECT_EQ(lever.misses_per_user.n, 2u);  // alice (0 misses) counts
  EXPECT_DOUBLE_EQ(lever.misses_per_user.mean, 0.5);
}

TEST(ComputeWorldTimes, EachWorldLastsUntilTheNextChangeOrTheEnd) {
  const std::vector<SceneChange> changes = {
      {kT0 + 25 * kSecond, "start_menu", "Start menu"},
      {kT0, "start_menu", "Start menu"},  // out of order on purpose
      {kT0 + 10 * kSecond, "solar_system", "Solar system"},
      {kT0 + 20 * kSecond, "solar_system", "Solar system (reloaded)"},  // a reload, not a visit
      {kT0 + 40 * kSecond, "dinosaur", "after the end: ignored"},
  };
  const auto worlds = ComputeWorldTimes(changes, kT0 + 30 * kSecond);
  ASSERT_EQ(worlds.size(), 2u);
  EXPECT_EQ(worlds[0].scene, "start_menu");
  EXPECT_EQ(worlds[0].visits, 2u);
  EXPECT_NEAR(worlds[0].seconds, 10.0 + 5.0, 1e-9);
  EXPECT_EQ(worlds[1].scene, "solar_system");
  EXPECT_EQ(worlds[1].visits, 1u);
  EXPECT_NEAR(worlds[1].seconds, 15.0, 1e-9);
  EXPECT_EQ(worlds[1].title, "Solar system (reloaded)");
  EXPECT_TRUE(ComputeWorldTimes({}, kT0).empty());
}

TEST(ComputeStays, PairsJoinsWithLeavesAndLosses) {
  const Member alice{"s/alice", "alice", "haptic", "sim", 1};
  const Member bob{"s/bob", "bob", "haptic", "hiro", 2};
  const Member screen{"s/screen", "screen", "graphics", "", 3};
  const auto stays = ComputeStays({
      {kT0 + 1, MemberChange::kJoined, alice},
      {kT0 + 2, MemberChange::kJoined, bob},
      {kT0 + 3, MemberChange::kLeft, alice},
      {kT0 + 4, MemberChange::kJoined, alice},  // rejoins
      {kT0 + 5, MemberChange::kLost, bob},
      {kT0 + 6, MemberChange::kJoined, screen},
      {kT0 + 7, MemberChange::kLeft, screen},
      {kT0 + 8, MemberChange::kLeft, screen},  // a second leave changes nothing
  });
  ASSERT_EQ(stays.size(), 4u);
  EXPECT_EQ(stays[0].member.user, "alice");
  EXPECT_EQ(stays[0].how, "left");
  EXPECT_EQ(stays[0].gone_unix_ns, kT0 + 3);
  EXPECT_EQ(stays[1].member.user, "bob");
  EXPECT_EQ(stays[1].how, "lost");
  EXPECT_EQ(stays[2].member.user, "alice");
  EXPECT_EQ(stays[2].how, "present at end");
  EXPECT_FALSE(stays[2].gone_unix_ns);
  EXPECT_EQ(stays[3].gone_unix_ns, kT0 + 7);
}

// Writes two sessions with SessionLog and reads them back through ReadReport.
class ReportFromFile : public ::testing::Test {
 protected:
  void SetUp() override {
    {
      SessionLog log(file_, SessionStart{"first", 121, "host1", 10, kT0});
      log.OnSceneChange("start_menu", "Start menu", kT0);
      log.End(kT0 + 5 * kSecond);
    }
    SessionLog log(file_, SessionStart{"second", 122, "host2", 20, kT0 + 100 * kSecond});
    const Member alice{"second/alice", "alice", "haptic", "sim", 21};
    log.OnSceneChange("start_menu", "Start menu", kT0 + 100 * kSecond);
    log.OnMember(MemberChange::kJoined, alice, kT0 + 101 * kSecond);
    log.OnSceneChange("solar_system", "Solar system", kT0 + 110 * kSecond);
    log.OnControlEvent({kT0 + 111 * kSecond, "alice", "lever", controls::EventKind::kMissed, 0.0, 0.010});
    log.OnControlEvent({kT0 + 112 * kSecond, "alice", "lever", controls::EventKind::kMoved, 0.4, 0.002});
    log.OnControlEvent({kT0 + 113 * kSecond, "alice", "button", controls::EventKind::kPressed, 1.0, 0.001});
    log.OnOwnership("ball", "alice", "granted", kT0 + 114 * kSecond);
    log.OnMember(MemberChange::kLeft, alice, kT0 + 115 * kSecond);
    log.End(kT0 + 120 * kSecond);
  }
  TempDir dir_;
  std::filesystem::path file_ = dir_ / "log.sqlite";
};

TEST_F(ReportFromFile, TheNewestSessionByDefault) {
  const SessionReport r = ReadReport(file_);
  EXPECT_EQ(r.sessions_in_file, 2u);
  EXPECT_EQ(r.session.id, 2);
  EXPECT_EQ(r.session.name, "second");
  EXPECT_EQ(r.session.domain_id, 122);
  ASSERT_TRUE(r.session.ended_unix_ns);
  EXPECT_EQ(*r.session.ended_unix_ns, kT0 + 120 * kSecond);
  ASSERT_EQ(r.worlds.size(), 2u);
  EXPECT_NEAR(r.worlds[0].seconds, 10.0, 1e-9);
  EXPECT_NEAR(r.worlds[1].seconds, 10.0, 1e-9);
  ASSERT_EQ(r.members.size(), 1u);
  EXPECT_EQ(r.members[0].how, "left");
  ASSERT_EQ(r.controls.size(), 2u);
  EXPECT_EQ(r.controls[1].control_id, "lever");
  EXPECT_EQ(r.controls[1].hits, 1u);
  EXPECT_EQ(r.controls[1].misses, 1u);
  EXPECT_EQ(r.controls[1].error_m.n, 1u);  // the hit; the miss's 10 mm is not a hit error
  EXPECT_NEAR(r.controls[1].error_m.mean, 0.002, 1e-12);
  EXPECT_EQ(r.control_events, 3u);
  EXPECT_EQ(r.ownership_changes, 1u);

  std::ostringstream text;
  PrintReport(text, r);
  const std::string t = text.str();
  EXPECT_NE(t.find("session #2 'second' on DDS domain 122"), std::string::npos) << t;
  EXPECT_NE(t.find("(20.000 s)"), std::string::npos) << t;
  EXPECT_NE(t.find("solar_system"), std::string::npos) << t;
  EXPECT_NE(t.find("  lever                 1       1        1       2.00       0.00      1      1.00    0.00"),
            std::string::npos)
      << t;
  std::ostringstream csv;
  PrintReportCsv(csv, r);
  const std::string c = csv.str();
  EXPECT_EQ(c.rfind("session,section,item,field,value\n", 0), 0u) << c;
  EXPECT_NE(c.find("2,control,lever,misses,1\n"), std::string::npos) << c;
  EXPECT_NE(c.find("2,world,solar_system,seconds,10.000\n"), std::string::npos) << c;
  EXPECT_NE(c.find("2,member,second/alice#1,how,left\n"), std::string::npos) << c;
  EXPECT_NE(c.find("2,session,2,duration_s,20.000\n"), std::string::npos) << c;
}

TEST_F(ReportFromFile, AnEarlierSessionByIdAndAnUnknownOne) {
  const SessionReport r = ReadReport(file_, 1);
  EXPECT_EQ(r.session.name, "first");
  ASSERT_EQ(r.worlds.size(), 1u);
  EXPECT_NEAR(r.worlds[0].seconds, 5.0, 1e-9);
  EXPECT_TRUE(r.controls.empty());
  const std::string error = ErrorOf([&] { ReadReport(file_, 3); });
  EXPECT_NE(error.find("no session 3 (sessions 1..2)"), std::string::npos) << error;
  EXPECT_EQ(ListSessions(file_).size(), 2u);
}

TEST_F(ReportFromFile, ASessionThatWasNotEndedRunsUntilItsLastHeartbeat) {
  {
    sqlite3* db = nullptr;
    ASSERT_EQ(sqlite3_open(file_.c_str(), &db), SQLITE_OK);
    const std::string sql = "UPDATE sessions SET ended_unix_ns = NULL, last_seen_unix_ns = " +
                            std::to_string(kT0 + 130 * kSecond) + " WHERE id = 2";
    EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK);
    sqlite3_close(db);
  }
  const SessionReport r = ReadReport(file_);
  EXPECT_FALSE(r.session.ended_unix_ns);
  EXPECT_NEAR(r.worlds[1].seconds, 20.0, 1e-9);
  std::ostringstream text;
  PrintReport(text, r);
  EXPECT_NE(text.str().find("not ended cleanly"), std::string::npos) << text.str();
}

// A session of visitors in a real log (SessionLog writes it, ReadReport reads it): the kinds of
// its controls, three visitors' turns and questionnaires, and control events. Every expected
// mean and sd below is worked out by hand from the rows (sample sd, n - 1).
class VisitReport : public ::testing::Test {
 protected:
  void SetUp() override {
    SessionLog log(file_, SessionStart{"museum", 123, "host", 30, kT0});
    scene::Scene world;
    world.name = "start_menu";
    world.controls = {testing::Control("button_a", scene::ControlType::kButton),
                      testing::Control("button_b", scene::ControlType::kButton),
                      testing::Control("lever_x", scene::ControlType::kLever)};
    log.OnControlKinds(world);
    log.OnSceneChange("start_menu", "Start menu", kT0);
    // Buttons: alice hits button_a (2 mm); bob misses button_b twice, then hits it (4 mm).
    // Lever: carol misses once, then hits (10 mm). "gone" is a control of no known kind.
    log.OnControlEvent({kT0 + 1 * kSecond, "alice", "button_a", controls::EventKind::kPressed, 1.0, 0.002});
    log.OnControlEvent({kT0 + 2 * kSecond, "alice", "button_a", controls::EventKind::kReleased, 0.0, std::nullopt});
    log.OnControlEvent({kT0 + 3 * kSecond, "bob", "button_b", controls::EventKind::kMissed, 0.0, 0.03});
    log.OnControlEvent({kT0 + 4 * kSecond, "bob", "button_b", controls::EventKind::kMissed, 0.0, 0.03});
    log.OnControlEvent({kT0 + 5 * kSecond, "bob", "button_b", controls::EventKind::kPressed, 1.0, 0.004});
    log.OnControlEvent({kT0 + 6 * kSecond, "carol", "lever_x", controls::EventKind::kMissed, 0.0, 0.05});
    log.OnControlEvent({kT0 + 7 * kSecond, "carol", "lever_x", controls::EventKind::kMoved, 0.4, 0.010});
    log.OnControlEvent({kT0 + 8 * kSecond, "carol", "gone", controls::EventKind::kPressed, 1.0, std::nullopt});
    log.OnTurnEnded(TurnRecord{kT0 + 10 * kSecond, kT0 + 70 * kSecond, "museum/alice", "alice"});
    log.OnTurnEnded(TurnRecord{kT0 + 20 * kSecond, kT0 + 80 * kSecond, "museum/bob", "bob"});
    // Button ease 5, 6, 7 (mean 6, sd 1); button naturalness 4, 4, 7 (mean 5, sd sqrt(3));
    // button satisfaction 7, 7, 7 (mean 7, sd 0); lever ease 2, 4 (mean 3, sd sqrt(2)), the
    // lever's other two 3, 6 (mean 4.5, sd sqrt(4.5)); nobody answered for arrows or books.
    log.OnVisitAnswers("console", Answers("alice", {{scene::ControlType::kButton, {5, 4, 7}}}), kT0 + 71 * kSecond);
    log.OnVisitAnswers("console", Answers("bob", {{scene::ControlType::kButton, {6, 4, 7}},
                                                  {scene::ControlType::kLever, {2, 3, 3}}}), kT0 + 81 * kSecond);
    log.OnVisitAnswers("console", Answers("carol", {{scene::ControlType::kButton, {7, 7, 7}},
                                                    {scene::ControlType::kLever, {4, 6, 6}}}), kT0 + 91 * kSecond);
    log.End(kT0 + 100 * kSecond);
  }
  static controls::VisitAnswers Answers(const std::string& visitor,
                                        const std::vector<std::pair<scene::ControlType, std::array<int, 3>>>& rows) {
    controls::VisitAnswers a;
    a.visitor = visitor;
    for (const auto& [kind, scores] : rows) {
      for (std::size_t q = 0; q < 3; ++q) a.scores[static_cast<std::size_t>(kind)][q] = static_cast<std::uint8_t>(scores[q]);
    }
    return a;
  }
  const QuestionStats& Question(const SessionReport& r, scene::ControlType kind, controls::VisitQuestion q) {
    for (const auto& row : r.questionnaire) {
      if (row.kind == kind && row.question == q) return row;
    }
    throw std::runtime_error("no questionnaire row");
  }
  TempDir dir_;
  std::filesystem::path file_ = dir_ / "visits.sqlite";
};

TEST_F(VisitReport, QuestionnaireCountMeanAndSdPerKindAndQuestion) {
  using controls::VisitQuestion;
  using scene::ControlType;
  const SessionReport r = ReadReport(file_);
  EXPECT_EQ(r.questionnaires, 3u);
  ASSERT_EQ(r.questionnaire.size(), 12u);  // every kind times every question
  EXPECT_EQ(r.questionnaire.front().kind, ControlType::kArrow);  // the paper's order
  EXPECT_EQ(r.questionnaire.back().kind, ControlType::kLever);
  const struct {
    ControlType kind;
    VisitQuestion q;
    std::size_t n;
    double mean, sd;
  } expected[] = {
      {ControlType::kButton, VisitQuestion::kEase, 3, 6.0, 1.0},
      {ControlType::kButton, VisitQuestion::kNaturalness, 3, 5.0, std::sqrt(3.0)},
      {ControlType::kButton, VisitQuestion::kSatisfaction, 3, 7.0, 0.0},
      {ControlType::kLever, VisitQuestion::kEase, 2, 3.0, std::sqrt(2.0)},
      {ControlType::kLever, VisitQuestion::kNaturalness, 2, 4.5, std::sqrt(4.5)},
      {ControlType::kLever, VisitQuestion::kSatisfaction, 2, 4.5, std::sqrt(4.5)},
      {ControlType::kArrow, VisitQuestion::kEase, 0, 0.0, 0.0},
      {ControlType::kBook, VisitQuestion::kSatisfaction, 0, 0.0, 0.0},
  };
  for (const auto& e : expected) {
    const QuestionStats& q = Question(r, e.kind, e.q);
    SCOPED_TRACE(std::string(controls::ToString(e.kind)) + "/" + controls::ToString(e.q));
    EXPECT_EQ(q.score.n, e.n);
    EXPECT_NEAR(q.score.mean, e.mean, 1e-12);
    EXPECT_NEAR(q.score.sd, e.sd, 1e-12);
  }
  std::ostringstream text;
  PrintReport(text, r);
  const std::string t = text.str();
  EXPECT_NE(t.find("questionnaire (the paper's Fig. 16 and Table 3): 3 questionnaire(s)"), std::string::npos) << t;
  EXPECT_NE(t.find("  button   ease             3   6.00   1.00\n"), std::string::npos) << t;
  EXPECT_NE(t.find("  button   naturalness      3   5.00   1.73\n"), std::string::npos) << t;
  EXPECT_NE(t.find("  lever    ease             2   3.00   1.41\n"), std::string::npos) << t;
  // No answer: no mean and no spread, shown as dashes rather than a 0.00 that reads as a score.
  EXPECT_NE(t.find("  arrow    ease             0      -      -\n"), std::string::npos) << t;
  std::ostringstream csv;
  PrintReportCsv(csv, r);
  const std::string c = csv.str();
  EXPECT_NE(c.find("1,questionnaire,button/ease,n,3\n"), std::string::npos) << c;
  EXPECT_NE(c.find("1,questionnaire,button/ease,mean,6\n"), std::string::npos) << c;
  EXPECT_NE(c.find("1,questionnaire,lever/satisfaction,mean,4.5\n"), std::string::npos) << c;
  EXPECT_NE(c.find("1,questionnaire,lever/ease,sd,1.41421\n"), std::string::npos) << c;
  EXPECT_NE(c.find("1,questionnaire,1,count,3\n"), std::string::npos) << c;
}

TEST_F(VisitReport, Table4ByKindOfControlBesideThePerControlRows) {
  const SessionReport r = ReadReport(file_);
  ASSERT_EQ(r.controls.size(), 4u);  // the per-control rows stay
  ASSERT_EQ(r.kinds.size(), 3u);
  // button: button_a and button_b; hits 2, misses 2; errors 2 and 4 mm (mean 3, sd sqrt(2));
  // misses per user alice 0, bob 2 (mean 1, sd sqrt(2)).
  const KindStats& button = r.kinds[0];
  EXPECT_EQ(button.kind, "button");
  EXPECT_EQ(button.controls, 2u);
  EXPECT_EQ(button.hits, 2u);
  EXPECT_EQ(button.misses, 2u);
  EXPECT_EQ(button.released, 1u);
  EXPECT_EQ(button.error_m.n, 2u);
  EXPECT_NEAR(button.error_m.mean, 0.003, 1e-12);
  EXPECT_NEAR(button.error_m.sd, std::sqrt(2.0) * 1e-3, 1e-12);
  EXPECT_EQ(button.misses_per_user.n, 2u);
  EXPECT_NEAR(button.misses_per_user.mean, 1.0, 1e-12);
  EXPECT_NEAR(button.misses_per_user.sd, std::sqrt(2.0), 1e-12);
  // lever: carol alone, 1 miss, one hit at 10 mm.
  const KindStats& lever = r.kinds[1];
  EXPECT_EQ(lever.kind, "lever");
  EXPECT_EQ(lever.misses_per_user.n, 1u);
  EXPECT_NEAR(lever.misses_per_user.mean, 1.0, 1e-12);
  EXPECT_NEAR(lever.error_m.mean, 0.010, 1e-12);
  // A control the log gives no kind for is counted, under "unknown", last.
  EXPECT_EQ(r.kinds[2].kind, "unknown");
  EXPECT_EQ(r.kinds[2].hits, 1u);

  std::ostringstream text;
  PrintReport(text, r);
  const std::string t = text.str();
  // The new tables come after every line the report printed before (a contract for readers).
  EXPECT_LT(t.find("ownership changes: 0\n"), t.find("controls by kind"));
  EXPECT_NE(t.find("  button          2      2       2        2       3.00       1.41      2      1.00    1.41\n"),
            std::string::npos)
      << t;
  EXPECT_NE(t.find("visitors' turns ended: 2\n"), std::string::npos) << t;
  EXPECT_NE(t.find("  bob                  20.000     80.000     60.000\n"), std::string::npos) << t;
  std::ostringstream csv;
  PrintReportCsv(csv, r);
  const std::string c = csv.str();
  EXPECT_NE(c.find("1,control_kind,button,misses_per_user_sd,1.41421\n"), std::string::npos) << c;
  EXPECT_NE(c.find("1,control_kind,lever,controls,1\n"), std::string::npos) << c;
  EXPECT_NE(c.find("1,turn,museum/alice#1,ended_s,70.000\n"), std::string::npos) << c;
  // The older sections come first, as before.
  EXPECT_LT(c.find("1,ownership,1,changes,0\n"), c.find("1,control_kind,"));
}

// A log of schema version 3 (no tables of visits) reads as before, every control of unknown kind.
TEST(ReadReport, ALogWithoutVisitTablesReportsNone) {
  TempDir dir;
  const auto file = dir / "v3.sqlite";
  {
    SessionLog log(file, SessionStart{"museum", 5, "h", 1, kT0});
    log.OnControlEvent({kT0 + kSecond, "alice", "lever_x", controls::EventKind::kMoved, 0.4, 0.002});
    log.End(kT0 + 2 * kSecond);
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, "DROP TABLE visit_turns; DROP TABLE visit_answers; DROP TABLE control_kinds; "
                             "PRAGMA user_version = 3;", nullptr, nullptr, nullptr),
            SQLITE_OK);
  sqlite3_close(db);
  const SessionReport r = ReadReport(file);
  EXPECT_TRUE(r.turns.empty());
  EXPECT_EQ(r.questionnaires, 0u);
  ASSERT_EQ(r.kinds.size(), 1u);
  EXPECT_EQ(r.kinds[0].kind, "unknown");
}

// The stations' loop statistics (schema version 5): per node its samples, rate, worst p99
// jitter and mean bytes per second, and the newest sample's counts; in the text and the CSV.
TEST(ReadReport, StationsSumUpEveryNodesLoopStatistics) {
  TempDir dir;
  const auto file = dir / "stations.sqlite";
  const auto loop = [](std::uint64_t t, const char* node, double rate_Hz, double jitter_p99_us, std::uint64_t overruns,
                       std::uint64_t deadline_misses, double bytes_per_s) {
    LoopRecord l;
    l.unix_ns = t;
    l.node = node;
    l.rate_Hz = rate_Hz;
    l.jitter_p99_us = jitter_p99_us;
    l.overruns = overruns;
    l.faults = 1;
    l.deadline_misses = deadline_misses;
    l.sent_bytes_per_s = bytes_per_s;
    return l;
  };
  {
    SessionLog log(file, SessionStart{"museum", 5, "h", 1, kT0});
    log.OnLoopStatistics(loop(kT0 + 1 * kSecond, "haptic_node/alice", 1000.0, 40.0, 0, 0, 2000.0));
    log.OnLoopStatistics(loop(kT0 + 2 * kSecond, "graphics_node/screen", 30.0, 900.0, 2, 1, 100.0));
    log.OnLoopStatistics(loop(kT0 + 2 * kSecond, "haptic_node/alice", 990.0, 60.0, 3, 2, 3000.0));
    log.End(kT0 + 3 * kSecond);
  }
  const SessionReport r = ReadReport(file);
  ASSERT_EQ(r.stations.size(), 2u);
  const StationStats& screen = r.stations[0];
  const StationStats& alice = r.stations[1];
  EXPECT_EQ(screen.node, "graphics_node/screen");
  EXPECT_EQ(screen.samples, 1u);
  EXPECT_EQ(screen.last.deadline_misses, 1u);
  EXPECT_EQ(alice.node, "haptic_node/alice");
  EXPECT_EQ(alice.samples, 2u);
  EXPECT_EQ(alice.first_unix_ns, kT0 + 1 * kSecond);
  EXPECT_EQ(alice.last_unix_ns, kT0 + 2 * kSecond);
  EXPECT_DOUBLE_EQ(alice.rate_mean_Hz, 995.0);
  EXPECT_DOUBLE_EQ(alice.rate_min_Hz, 990.0);
  EXPECT_DOUBLE_EQ(alice.jitter_p99_max_us, 60.0);
  EXPECT_DOUBLE_EQ(alice.sent_bytes_per_s_mean, 2500.0);
  EXPECT_DOUBLE_EQ(alice.last.rate_Hz, 990.0);
  EXPECT_EQ(alice.last.overruns, 3u);
  EXPECT_EQ(alice.last.faults, 1u);
  EXPECT_EQ(alice.last.deadline_misses, 2u);
  EXPECT_DOUBLE_EQ(alice.last.sent_bytes_per_s, 3000.0);
  std::ostringstream text, csv;
  PrintReport(text, r);
  PrintReportCsv(csv, r);
  EXPECT_NE(text.str().find("stations (loop statistics"), std::string::npos) << text.str();
  EXPECT_NE(text.str().find("haptic_node/alice"), std::string::npos) << text.str();
  EXPECT_NE(csv.str().find("station,haptic_node/alice,deadline_misses,2\n"), std::string::npos) << csv.str();
  EXPECT_NE(csv.str().find("station,haptic_node/alice,sent_bytes_per_s_mean,2500\n"), std::string::npos) << csv.str();

  // A log of version 4 has none, and opening it to write migrates it and keeps its rows.
  const auto old_file = dir / "v4.sqlite";
  {
    SessionLog log(old_file, SessionStart{"museum", 5, "h", 1, kT0});
    log.OnSceneChange("start_menu", "Start menu", kT0);
  }
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(old_file.c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, "DROP TABLE loop_statistics; PRAGMA user_version = 4;", nullptr, nullptr, nullptr), SQLITE_OK);
  sqlite3_close(db);
  EXPECT_TRUE(ReadReport(old_file).stations.empty());
  {
    SessionLog log(old_file, SessionStart{"museum", 5, "h", 1, kT0 + 10 * kSecond});
    log.OnLoopStatistics(loop(kT0 + 11 * kSecond, "audio_guide/guide", 20.0, 0.0, 0, 0, 50.0));
  }
  EXPECT_EQ(ListSessions(old_file).size(), 2u);
  const SessionReport migrated = ReadReport(old_file);
  ASSERT_EQ(migrated.stations.size(), 1u);
  EXPECT_EQ(migrated.stations[0].node, "audio_guide/guide");
  EXPECT_EQ(ReadReport(old_file, ListSessions(old_file).front().id).worlds.size(), 1u);
}

TEST(ReadReport, MissingEmptyForeignAndCorruptFilesSayWhat) {
  TempDir dir;
  EXPECT_NE(ErrorOf([&] { ReadReport(dir / "absent.sqlite"); }).find("absent.sqlite: no such file"),
            std::string::npos);
  EXPECT_NE(ErrorOf([&] { ReadReport(dir.path()); }).find("is a directory"), std::string::npos);

  const auto empty = dir / "empty.sqlite";
  std::ofstream(empty).close();
  EXPECT_NE(ErrorOf([&] { ReadReport(empty); }).find("empty file"), std::string::npos);

  const auto text = dir / "text.sqlite";
  std::ofstream(text) << "hello, not a database at all, but long enough to look like a header ...........";
  std::string error = ErrorOf([&] { ReadReport(text); });
  EXPECT_NE(error.find(text.string()), std::string::npos) << error;
  EXPECT_NE(error.find("not a database"), std::string::npos) << error;

  // A real log whose pages after the header are overwritten: the header still says "handshare
  // log", the tables do not read.
  const auto broken = dir / "broken.sqlite";
  {
    SessionLog log(broken, SessionStart{"x", 120, "h", 1, kT0});
    log.OnSceneChange("start_menu", "", kT0);
  }
  ASSERT_GT(std::filesystem::file_size(broken), 4096u);
  {
    std::fstream f(broken, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(100);
    const std::string garbage(8000, '\x5a');
    f.write(garbage.data(), static_cast<std::streamsize>(garbage.size()));
  }
  error = ErrorOf([&] { ReadReport(broken); });
  EXPECT_NE(error.find(broken.string()), std::string::npos) << error;
  EXPECT_NE(error.find("malformed"), std::string::npos) << error;
}

}  // namespace
}  // namespace handshare::server
