#pragma once
/// What the console checks of every request from a browser, as plain functions (no sockets):
/// the operator's token, the one action's body, the Origin of a state-changing request, and
/// how often one address may ask. The web server (web_server.cpp) calls these; each bad input
/// maps to a 4xx status there. Not real-time.
#include <chrono>
#include <cstddef>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>

#include "handshare/controls/visit_answers.hpp"
#include "handshare/controls/operator_command.hpp"

namespace handshare::web_console {

/// The operator's token from `file`: its content without surrounding white space. Throws
/// std::runtime_error naming the file if it cannot be read, or if the token is shorter than
/// kMinTokenChars, longer than kMaxTokenChars or holds a character outside printable ASCII
/// (space excluded): a guessable or mangled token is refused at start, not at the first action.
std::string ReadTokenFile(const std::filesystem::path& file);
inline constexpr std::size_t kMinTokenChars = 16;
inline constexpr std::size_t kMaxTokenChars = 256;

/// The token of an "Authorization: Bearer TOKEN" header value; empty if it is not one.
std::optional<std::string> BearerToken(std::string_view authorization);

/// a == b, in time that depends on the lengths only (no early exit on the first difference).
bool TokensEqual(std::string_view a, std::string_view b) noexcept;

/// POST /api/world's body: exactly {"world": NAME}, NAME 1 to 64 of [a-z0-9_].
struct WorldRequest {
  std::string world;
};
struct ParsedWorldRequest {
  std::optional<WorldRequest> request;
  std::string error;  ///< why not, when request is empty
};
inline constexpr std::size_t kMaxActionBodyBytes = 1024;
ParsedWorldRequest ParseWorldRequest(std::string_view body);

/// POST /api/visit's body: a visitor's questionnaire, exactly
///   {"visitor": NAME, "answers": {KIND: {"ease": S, "naturalness": S, "satisfaction": S}, ...}}
/// NAME 1 to 64 of [A-Za-z0-9_.-]; KIND one of button, arrow, lever, book, at least one (a kind the visitor did not use is left out); every score an integer 1 to 7, all
/// three given. Anything else (another field, a float, a string, 0 or 8) is refused.
struct ParsedVisitRequest {
  std::optional<controls::VisitAnswers> answers;
  std::string error;  ///< why not, when answers is empty
};
ParsedVisitRequest ParseVisitRequest(std::string_view body);

/// POST /api/command's body: an operator's command other than a world change (that is
/// POST /api/world), exactly {"command": "restart_tour"} or {"command": "end_turn", "visitor":
/// NAME}, NAME 1 to 64 of [A-Za-z0-9_.-]. Anything else is refused.
struct ParsedCommandRequest {
  std::optional<controls::OperatorCommand> command;
  std::string error;  ///< why not, when command is empty
};
ParsedCommandRequest ParseCommandRequest(std::string_view body);

/// A browser's Origin header against the Host header it sent: a page of another site may not
/// act on the console nor open its socket (cross-site request forgery, cross-site WebSocket
/// hijacking). An absent Origin (curl, a test's HTTP client) is allowed; "null" is not.
bool OriginAllowed(std::optional<std::string_view> origin, std::string_view host, bool tls);

/// A token bucket: `burst` requests at once, then `rate_per_s` a second.
class TokenBucket {
 public:
  using Clock = std::chrono::steady_clock;
  TokenBucket(double rate_per_s, double burst, Clock::time_point now);
  /// Takes one token if there is one.
  bool Take(Clock::time_point now);
  /// Full again (an idle client's bucket can be forgotten).
  bool Full(Clock::time_point now) const;
  /// Whole seconds until a token is there (at least 1): a refusal's Retry-After.
  int SecondsToNextToken(Clock::time_point now) const;

 private:
  double rate_per_s_;
  double burst_;
  double tokens_;
  Clock::time_point last_;
};

/// One bucket per remote address, at most `max_addresses` of them: full buckets are forgotten
/// when the table is full, and while it is still full a new address is refused.
class RateLimiter {
 public:
  RateLimiter(double rate_per_s, double burst, std::size_t max_addresses = 1024);
  bool Allow(const std::string& address, TokenBucket::Clock::time_point now);
  /// After a refusal: whole seconds until `address` may ask again (RFC 9110's Retry-After).
  int RetryAfterS(const std::string& address, TokenBucket::Clock::time_point now) const;

 private:
  double rate_per_s_;
  double burst_;
  std::size_t max_addresses_;
  std::map<std::string, TokenBucket> buckets_;
};

}  // namespace handshare::web_console
