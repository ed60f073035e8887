#include "handshare/web_console/request_checks.hpp"

#include <gtest/gtest.h>

#include <fstream>

namespace handshare::web_console {
namespace {

std::filesystem::path WriteTemp(const std::string& name, const std::string& content) {
  const auto path = std::filesystem::temp_directory_path() / ("web_console_test_" + std::to_string(getpid()) + "_" + name);
  std::ofstream(path) << content;
  return path;
}

TEST(ReadTokenFile, TrimsAndRefusesShortOrOddTokens) {
  EXPECT_EQ(ReadTokenFile(WriteTemp("ok", "  0123456789abcdefXYZ\n")), "0123456789abcdefXYZ");
  EXPECT_THROW(ReadTokenFile(WriteTemp("short", "short\n")), std::runtime_error);
  EXPECT_THROW(ReadTokenFile(WriteTemp("space", "0123456789 abcdefXYZ\n")), std::runtime_error);
  EXPECT_THROW(ReadTokenFile(WriteTemp("empty", " \n")), std::runtime_error);
  EXPECT_THROW(ReadTokenFile("/nonexistent/token"), std::runtime_error);
}

TEST(BearerToken, OnlyTheBearerScheme) {
  EXPECT_EQ(BearerToken("Bearer abc"), std::optional<std::string>("abc"));
  EXPECT_FALSE(BearerToken("Basic abc"));
  EXPECT_FALSE(BearerToken("Bearer "));
  EXPECT_FALSE(BearerToken("Bearer a b"));
  EXPECT_FALSE(BearerToken(""));
}

TEST(TokensEqual, EqualOnlyWhenTheSame) {
  EXPECT_TRUE(TokensEqual("0123456789abcdef", "0123456789abcdef"));
  EXPECT_FALSE(TokensEqual("0123456789abcdef", "0123456789abcdeg"));
  EXPECT_FALSE(TokensEqual("0123456789abcdef", "0123456789abcde"));
  EXPECT_FALSE(TokensEqual("", "x"));
}

TEST(ParseVisitRequest, AcceptsAVisitorAndTheThreeScoresOfEachKindAnswered) {
  const auto ok = ParseVisitRequest(
      R"({"visitor": "alice.B-2", "answers": {"button": {"ease": 1, "naturalness": 4, "satisfaction": 7},
                                              "lever": {"satisfaction": 2, "ease": 3, "naturalness": 5}}})");
  ASSERT_TRUE(ok.answers) << ok.error;
  EXPECT_EQ(ok.answers->visitor, "alice.B-2");
  using controls::VisitQuestion;
  using scene::ControlType;
  EXPECT_EQ(ok.answers->at(ControlType::kButton, VisitQuestion::kEase), 1);
  EXPECT_EQ(ok.answers->at(ControlType::kButton, VisitQuestion::kSatisfaction), 7);
  EXPECT_EQ(ok.answers->at(ControlType::kLever, VisitQuestion::kEase), 3);
  EXPECT_EQ(ok.answers->at(ControlType::kLever, VisitQuestion::kSatisfaction), 2);
  EXPECT_EQ(ok.answers->at(ControlType::kArrow, VisitQuestion::kEase), 0);  // not used: not answered
  EXPECT_EQ(ok.answers->at(ControlType::kBook, VisitQuestion::kNaturalness), 0);
}

TEST(ParseVisitRequest, RefusesEverythingElseSayingWhat) {
  const std::string three = R"({"ease": 5, "naturalness": 5, "satisfaction": 5})";
  const struct {
    std::string body;
    const char* says;
  } cases[] = {
      {"", "not JSON"},
      {"[1]", "not a JSON object"},
      {R"({"answers": {"book": )" + three + "}}", "'visitor' missing"},
      {R"({"visitor": "", "answers": {"book": )" + three + "}}", "'visitor' is not"},
      {R"({"visitor": ")" + std::string(65, 'a') + R"(", "answers": {"book": )" + three + "}}", "'visitor' is not"},
      {R"({"visitor": "<b>", "answers": {"book": )" + three + "}}", "'visitor' is not"},
      {R"({"visitor": 7, "answers": {"book": )" + three + "}}", "'visitor' missing or not a string"},
      {R"({"visitor": "a"})", "'answers' missing"},
      {R"({"visitor": "a", "answers": {}})", "or empty"},
      {R"({"visitor": "a", "answers": [1]})", "not an object"},
      {R"({"visitor": "a", "answers": {"book": )" + three + R"(}, "rating": 1})", "unknown field 'rating'"},
      {R"({"visitor": "a", "answers": {"sword": )" + three + "}}", "'sword' is not button, arrow, lever or book"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 5, "naturalness": 5}}})", "answers.book: not an object"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 5, "naturalness": 5, "satisfaction": 5, "fun": 5}}})",
       "answers.book: not an object"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 5, "naturalness": 5, "fun": 5}}})", "'fun' is not ease"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 8, "naturalness": 5, "satisfaction": 5}}})",
       "answers.book.ease: not an integer from 1 to 7"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 0, "naturalness": 5, "satisfaction": 5}}})", "from 1 to 7"},
      {R"({"visitor": "a", "answers": {"book": {"ease": -3, "naturalness": 5, "satisfaction": 5}}})", "from 1 to 7"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 4.5, "naturalness": 5, "satisfaction": 5}}})", "from 1 to 7"},
      {R"({"visitor": "a", "answers": {"book": {"ease": "4", "naturalness": 5, "satisfaction": 5}}})", "from 1 to 7"},
      {R"({"visitor": "a", "answers": {"book": {"ease": true, "naturalness": 5, "satisfaction": 5}}})", "from 1 to 7"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 1e400, "naturalness": 5, "satisfaction": 5}}})", "not JSON"},
      {R"({"visitor": "a", "answers": {"book": {"ease": 4294967301, "naturalness": 5, "satisfaction": 5}}})",
       "from 1 to 7"},
      {std::string(kMaxActionBodyBytes + 1, ' '), "bytes (at most 1024)"},
  };
  for (const auto& c : cases) {
    const auto p = ParseVisitRequest(c.body);
    EXPECT_FALSE(p.answers) << c.body;
    EXPECT_NE(p.error.find(c.says), std::string::npos) << c.body << " -> " << p.error;
  }
}

TEST(ParseWorldRequest, AcceptsExactlyOneWorldName) {
  const auto ok = ParseWorldRequest(R"({"world": "solar_system"})");
  ASSERT_TRUE(ok.request) << ok.error;
  EXPECT_EQ(ok.request->world, "solar_system");
  for (const char* bad : {"", "[]", "{}", "not json", R"({"world": 3})", R"({"world": ""})",
                          R"({"world": "Solar"})", R"({"world": "../etc"})", R"({"world": "a", "extra": 1})"}) {
    const auto p = ParseWorldRequest(bad);
    EXPECT_FALSE(p.request) << bad;
    EXPECT_FALSE(p.error.empty()) << bad;
  }
  EXPECT_FALSE(ParseWorldRequest(R"({"world": ")" + std::string(65, 'a') + "\"}").request);
  EXPECT_FALSE(ParseWorldRequest(std::string(kMaxActionBodyBytes + 1, ' ')).request);
}

// The operator's commands other than a world change: exactly restart_tour, or end_turn with a
// visitor's name; anything else says what is wrong.
TEST(ParseCommandRequest, AcceptsRestartingTheTourAndEndingANamedVisitorsTurn) {
  const auto restart = ParseCommandRequest(R"({"command": "restart_tour"})");
  ASSERT_TRUE(restart.command) << restart.error;
  EXPECT_EQ(restart.command->action, controls::OperatorAction::kRestartTour);
  const auto end = ParseCommandRequest(R"({"command": "end_turn", "visitor": "alice.b-2"})");
  ASSERT_TRUE(end.command) << end.error;
  EXPECT_EQ(end.command->action, controls::OperatorAction::kEndTurn);
  EXPECT_EQ(end.command->visitor, "alice.b-2");
  for (const char* bad : {"", "[]", "{}", R"({"command": 1})", R"({"command": "reboot"})",
                          R"({"command": "go_to_world", "world": "dinosaur"})", R"({"command": "end_turn"})",
                          R"({"command": "end_turn", "visitor": ""})", R"({"command": "end_turn", "visitor": "al ice"})",
                          R"({"command": "end_turn", "visitor": 7})", R"({"command": "restart_tour", "visitor": "alice"})",
                          R"({"command": "restart_tour", "extra": 1})"}) {
    const auto p = ParseCommandRequest(bad);
    EXPECT_FALSE(p.command) << bad;
    EXPECT_FALSE(p.error.empty()) << bad;
  }
  EXPECT_EQ(ParseCommandRequest(R"({"command": "reboot"})").error, "command 'reboot' is not restart_tour or end_turn");
  EXPECT_FALSE(ParseCommandRequest(R"({"command": "end_turn", "visitor": ")" + std::string(65, 'a') + "\"}").command);
}

TEST(OriginAllowed, SameOriginOrNone) {
  EXPECT_TRUE(OriginAllowed(std::nullopt, "127.0.0.1:8080", false));
  EXPECT_TRUE(OriginAllowed("http://127.0.0.1:8080", "127.0.0.1:8080", false));
  EXPECT_FALSE(OriginAllowed("https://127.0.0.1:8080", "127.0.0.1:8080", false));
  EXPECT_TRUE(OriginAllowed("https://console.lab:8443", "console.lab:8443", true));
  EXPECT_FALSE(OriginAllowed("http://evil.example", "127.0.0.1:8080", false));
  EXPECT_FALSE(OriginAllowed("null", "127.0.0.1:8080", false));
  EXPECT_FALSE(OriginAllowed("http://127.0.0.1:8080", "", false));
}

TEST(RateLimiter, BurstThenRatePerAddress) {
  using namespace std::chrono_literals;
  const auto t0 = TokenBucket::Clock::time_point{} + 100s;
  RateLimiter limiter(/*rate_per_s=*/1.0, /*burst=*/3.0, /*max_addresses=*/2);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(limiter.Allow("a", t0));
  EXPECT_FALSE(limiter.Allow("a", t0));
  EXPECT_TRUE(limiter.Allow("b", t0));           // another address has its own bucket
  EXPECT_FALSE(limiter.Allow("c", t0));          // table full of busy addresses: refused
  EXPECT_TRUE(limiter.Allow("a", t0 + 1100ms));  // one more a second
  EXPECT_FALSE(limiter.Allow("a", t0 + 1200ms));
  EXPECT_TRUE(limiter.Allow("c", t0 + 10s));     // the idle ones are forgotten
}

TEST(RateLimiter, ARefusalSaysWhenToAskAgain) {
  using namespace std::chrono_literals;
  const auto t0 = TokenBucket::Clock::time_point{} + 100s;
  RateLimiter limiter(/*rate_per_s=*/0.2, /*burst=*/2.0, /*max_addresses=*/1);  // a token every 5 s
  EXPECT_TRUE(limiter.Allow("a", t0));
  EXPECT_TRUE(limiter.Allow("a", t0));
  EXPECT_FALSE(limiter.Allow("a", t0));
  EXPECT_EQ(limiter.RetryAfterS("a", t0), 5);
  EXPECT_EQ(limiter.RetryAfterS("a", t0 + 3500ms), 2);  // 1.5 s rounded up
  EXPECT_FALSE(limiter.Allow("a", t0 + 4900ms));
  EXPECT_EQ(limiter.RetryAfterS("a", t0 + 4900ms), 1);  // never 0: asked again at once it is refused
  EXPECT_TRUE(limiter.Allow("a", t0 + 5s));
  EXPECT_FALSE(limiter.Allow("b", t0 + 5s));            // table full of a busy address
  EXPECT_EQ(limiter.RetryAfterS("b", t0 + 5s), 10);     // a full bucket's refill at most
}

}  // namespace
}  // namespace handshare::web_console
