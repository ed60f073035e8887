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

}  // namespace
}  // namespace handshare::web_console
