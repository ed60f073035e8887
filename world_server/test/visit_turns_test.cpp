// A visitor's turn: world_server --visit-minutes (checked as every option is), the turns of the
// members present, and the board's message when one is over.
#include "handshare/world_server/visit_turns.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "handshare/common/utf8.hpp"
#include "handshare/node/node_main.hpp"
#include "handshare/world_server/world_server.hpp"

namespace handshare::server {
namespace {

using Clock = VisitTurns::Clock;

// world_server's options parsed from `args` (after the program's name), as its main does.
WorldServerConfig Parse(const std::vector<std::string>& args) {
  common::Options options("world_server", "test");
  node::DeclareSessionOptions(options);
  DeclareWorldServerOptions(options);
  std::vector<std::string> all{"world_server"};
  all.insert(all.end(), args.begin(), args.end());
  std::vector<const char*> argv;
  for (const std::string& a : all) argv.push_back(a.c_str());
  options.Parse(static_cast<int>(argv.size()), argv.data());
  return ReadWorldServerOptions(options);
}

std::string OptionErrorOf(const std::vector<std::string>& args) {
  try {
    Parse(args);
  } catch (const common::OptionError& e) {
    return e.what();
  }
  return "<no OptionError>";
}

TEST(VisitMinutesOption, ThePapersTenMinutesByDefaultFractionsAndZero) {
  EXPECT_DOUBLE_EQ(Parse({"--session", "s"}).visit_minutes, 10.0);
  EXPECT_DOUBLE_EQ(Parse({"--session", "s", "--visit-minutes", "0.05"}).visit_minutes, 0.05);
  EXPECT_DOUBLE_EQ(Parse({"--session", "s", "--visit-minutes", "0"}).visit_minutes, 0.0);
  EXPECT_DOUBLE_EQ(Parse({"--session", "s", "--visit-minutes", "1440"}).visit_minutes, 1440.0);
}

TEST(VisitMinutesOption, ABadValueSaysWhichOptionAndItsRange) {
  for (const char* bad : {"-1", "abc", "", "nan", "inf", "1441", "5min"}) {
    SCOPED_TRACE(bad);
    const std::string error = OptionErrorOf({"--session", "s", "--visit-minutes", bad});
    EXPECT_NE(error.find("option --visit-minutes: '" + std::string(bad) + "' is not a number in [0, 1440]"),
              std::string::npos)
        << error;
  }
}

Member Haptic(const std::string& user) { return Member{"s/" + user, user, "haptic", "sim", 1}; }

TEST(VisitTurns, EachVisitorsTurnEndsOnceItsLengthAfterItsJoin) {
  VisitTurns turns(std::chrono::seconds(3));
  const Clock::time_point t0{};
  turns.OnMember(MemberChange::kJoined, Haptic("alice"), t0);
  turns.OnMember(MemberChange::kJoined, Haptic("bob"), t0 + std::chrono::seconds(1));
  turns.OnMember(MemberChange::kJoined, Member{"s/screen", "screen", "graphics", "", 2}, t0);
  // Announced again while present (a partition healed): the turn keeps its start.
  turns.OnMember(MemberChange::kJoined, Haptic("alice"), t0 + std::chrono::seconds(2));
  EXPECT_TRUE(turns.TakeEnded(t0 + std::chrono::milliseconds(2999)).empty());
  auto ended = turns.TakeEnded(t0 + std::chrono::seconds(3));
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].member.user, "alice");
  EXPECT_EQ(ended[0].turn, std::chrono::seconds(3));
  ended = turns.TakeEnded(t0 + std::chrono::seconds(10));
  ASSERT_EQ(ended.size(), 1u);  // bob; alice's and the screen's never again
  EXPECT_EQ(ended[0].member.user, "bob");
  EXPECT_TRUE(turns.TakeEnded(t0 + std::chrono::seconds(20)).empty());
}

TEST(VisitTurns, AVisitorWhoLeavesOrIsLostHasNoTurnToEndAndZeroTurnsItOff) {
  VisitTurns turns(std::chrono::seconds(3));
  const Clock::time_point t0{};
  turns.OnMember(MemberChange::kJoined, Haptic("alice"), t0);
  turns.OnMember(MemberChange::kJoined, Haptic("bob"), t0);
  turns.OnMember(MemberChange::kLeft, Haptic("alice"), t0 + std::chrono::seconds(1));
  turns.OnMember(MemberChange::kLost, Haptic("bob"), t0 + std::chrono::seconds(1));
  EXPECT_TRUE(turns.TakeEnded(t0 + std::chrono::seconds(5)).empty());
  VisitTurns off(Clock::duration::zero());
  EXPECT_FALSE(off.enabled());
  off.OnMember(MemberChange::kJoined, Haptic("alice"), t0);
  EXPECT_TRUE(off.TakeEnded(t0 + std::chrono::hours(24)).empty());
}

// The board's two languages, as every scene's messages: English, and Japanese with a reading
// the ja voice can speak (kana and ASCII only, as the scene loader requires of scene files).
TEST(TurnOverMessages, EnglishAndJapaneseWithASpeakableReading) {
  const auto messages = TurnOverMessages("alice", 10.0);
  ASSERT_EQ(messages.size(), 2u);
  EXPECT_EQ(messages[0].language, "en");
  EXPECT_EQ(messages[0].text, "Thank you, alice: your 10 minutes are over.");
  EXPECT_NE(messages[0].next_action.find("questionnaire"), std::string::npos);
  EXPECT_TRUE(messages[0].reading.empty());
  EXPECT_EQ(messages[1].language, "ja");
  EXPECT_NE(messages[1].text.find("10分"), std::string::npos);
  EXPECT_FALSE(messages[1].next_action.empty());
  ASSERT_FALSE(messages[1].reading.empty());
  EXPECT_EQ(common::FirstOutsideKanaReading(messages[1].reading), std::nullopt) << messages[1].reading;
  // The board's limits (IDL MessageBoard: text 1024, next_action 512, reading 2048 bytes).
  for (const auto& m : TurnOverMessages(std::string(64, 'u'), 0.05)) {
    EXPECT_LT(m.text.size(), 1024u);
    EXPECT_LT(m.next_action.size(), 512u);
    EXPECT_LT(m.reading.size(), 2048u);
  }
}

}  // namespace
}  // namespace handshare::server
