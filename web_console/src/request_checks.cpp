#include "handshare/web_console/request_checks.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

namespace handshare::web_console {

namespace {
bool IsTokenChar(char c) { return c > ' ' && c < 127; }
bool IsWorldChar(char c) { return (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_'; }
bool IsUserChar(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' || c == '-';
}

// A JSON body's object, or why not (size first: nothing over the limit is parsed).
std::optional<nlohmann::json> ParseObject(std::string_view body, std::string& error) {
  if (body.size() > kMaxActionBodyBytes) {
    error = "body of " + std::to_string(body.size()) + " bytes (at most " + std::to_string(kMaxActionBodyBytes) + ")";
    return {};
  }
  nlohmann::json j = nlohmann::json::parse(body.begin(), body.end(), nullptr, /*allow_exceptions=*/false);
  if (j.is_discarded()) {
    error = "body is not JSON";
    return {};
  }
  if (!j.is_object()) {
    error = "body is not a JSON object";
    return {};
  }
  return j;
}
}  // namespace

std::string ReadTokenFile(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("--token-file " + file.string() + ": cannot be read");
  std::ostringstream all;
  all << in.rdbuf();
  std::string token = all.str();
  const auto first = token.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) throw std::runtime_error("--token-file " + file.string() + ": empty");
  token = token.substr(first, token.find_last_not_of(" \t\r\n") - first + 1);
  if (token.size() < kMinTokenChars || token.size() > kMaxTokenChars) {
    throw std::runtime_error("--token-file " + file.string() + ": the token has " + std::to_string(token.size()) +
                             " characters, not " + std::to_string(kMinTokenChars) + " to " +
                             std::to_string(kMaxTokenChars) + " (make one with: head -c 24 /dev/urandom | base64)");
  }
  if (!std::all_of(token.begin(), token.end(), IsTokenChar)) {
    throw std::runtime_error("--token-file " + file.string() +
                             ": the token holds a space or a character outside printable ASCII");
  }
  return token;
}

std::optional<std::string> BearerToken(std::string_view authorization) {
  constexpr std::string_view kScheme = "Bearer ";
  if (authorization.size() <= kScheme.size() || authorization.substr(0, kScheme.size()) != kScheme) return {};
  const std::string_view token = authorization.substr(kScheme.size());
  if (token.size() > kMaxTokenChars || !std::all_of(token.begin(), token.end(), IsTokenChar)) return {};
  return std::string(token);
}

bool TokensEqual(std::string_view a, std::string_view b) noexcept {
  // Every byte of the longer one is looked at, whatever differs first.
  const std::size_t n = std::max(a.size(), b.size());
  unsigned diff = a.size() == b.size() ? 0u : 1u;
  for (std::size_t i = 0; i < n; ++i) {
    const unsigned char x = i < a.size() ? static_cast<unsigned char>(a[i]) : 0;
    const unsigned char y = i < b.size() ? static_cast<unsigned char>(b[i]) : 0;
    diff |= static_cast<unsigned>(x ^ y);
  }
  return diff == 0;
}

ParsedWorldRequest ParseWorldRequest(std::string_view body) {
  ParsedWorldRequest out;
  const auto parsed = ParseObject(body, out.error);
  if (!parsed) return out;
  const nlohmann::json& j = *parsed;
  for (const auto& [key, value] : j.items()) {
    if (key != "world") {
      out.error = "unknown field '" + key.substr(0, 64) + "' (the only field is 'world')";
      return out;
    }
  }
  if (!j.contains("world") || !j["world"].is_string()) {
    out.error = "field 'world' missing or not a string";
    return out;
  }
  const std::string world = j["world"].get<std::string>();
  if (world.empty() || world.size() > 64 || !std::all_of(world.begin(), world.end(), IsWorldChar)) {
    out.error = "field 'world' is not 1 to 64 of a-z, 0-9, _";
    return out;
  }
  out.request = WorldRequest{world};
  return out;
}

ParsedVisitRequest ParseVisitRequest(std::string_view body) {
  ParsedVisitRequest out;
  const auto j = ParseObject(body, out.error);
  if (!j) return out;
  for (const auto& [key, value] : j->items()) {
    if (key != "visitor" && key != "answers") {
      out.error = "unknown field '" + key.substr(0, 64) + "' (the fields are 'visitor' and 'answers')";
      return out;
    }
  }
  if (!j->contains("visitor") || !(*j)["visitor"].is_string()) {
    out.error = "field 'visitor' missing or not a string";
    return out;
  }
  controls::VisitAnswers answers;
  answers.visitor = (*j)["visitor"].get<std::string>();
  if (answers.visitor.empty() || answers.visitor.size() > 64 ||
      !std::all_of(answers.visitor.begin(), answers.visitor.end(), IsUserChar)) {
    out.error = "field 'visitor' is not 1 to 64 of A-Z, a-z, 0-9, _, ., -";
    return out;
  }
  if (!j->contains("answers") || !(*j)["answers"].is_object() || (*j)["answers"].empty()) {
    out.error = "field 'answers' missing, not an object, or empty";
    return out;
  }
  for (const auto& [kind_name, questions] : (*j)["answers"].items()) {
    const auto kind = controls::ControlTypeFromString(kind_name);
    if (!kind) {
      out.error = "answers: '" + kind_name.substr(0, 64) + "' is not button, arrow, lever or book";
      return out;
    }
    if (!questions.is_object() || questions.size() != controls::kVisitQuestions) {
      out.error = "answers." + kind_name + ": not an object of ease, naturalness and satisfaction";
      return out;
    }
    for (const auto& [question_name, score] : questions.items()) {
      const auto question = controls::VisitQuestionFromString(question_name);
      if (!question) {
        out.error = "answers." + kind_name + ": '" + question_name.substr(0, 64) +
                    "' is not ease, naturalness or satisfaction";
        return out;
      }
      // An integer, not 5.0 nor "5" nor true: the page sends the radio button's number.
      if (!score.is_number_integer() || score.get<std::int64_t>() < controls::kMinScore ||
          score.get<std::int64_t>() > controls::kMaxScore) {
        out.error = "answers." + kind_name + "." + question_name + ": not an integer from 1 to 7";
        return out;
      }
      answers.at(*kind, *question) = static_cast<std::uint8_t>(score.get<std::int64_t>());
    }
  }
  out.answers = std::move(answers);
  return out;
}

ParsedCommandRequest ParseCommandRequest(std::string_view body) {
  ParsedCommandRequest out;
  const auto parsed = ParseObject(body, out.error);
  if (!parsed) return out;
  const nlohmann::json& j = *parsed;
  for (const auto& [key, value] : j.items()) {
    if (key != "command" && key != "visitor") {
      out.error = "unknown field '" + key.substr(0, 64) + "' (the fields are 'command' and, to end a turn, 'visitor')";
      return out;
    }
  }
  if (!j.contains("command") || !j["command"].is_string()) {
    out.error = "field 'command' missing or not a string";
    return out;
  }
  const std::string command = j["command"].get<std::string>();
  controls::OperatorCommand c;
  if (command == "restart_tour") {
    if (j.contains("visitor")) {
      out.error = "restart_tour takes no 'visitor'";
      return out;
    }
    c.action = controls::OperatorAction::kRestartTour;
  } else if (command == "end_turn") {
    if (!j.contains("visitor") || !j["visitor"].is_string()) {
      out.error = "end_turn: field 'visitor' missing or not a string";
      return out;
    }
    c.visitor = j["visitor"].get<std::string>();
    if (c.visitor.empty() || c.visitor.size() > 64 || !std::all_of(c.visitor.begin(), c.visitor.end(), IsUserChar)) {
      out.error = "end_turn: field 'visitor' is not 1 to 64 of A-Z, a-z, 0-9, _, ., -";
      return out;
    }
    c.action = controls::OperatorAction::kEndTurn;
  } else {
    out.error = "command '" + command.substr(0, 64) + "' is not restart_tour or end_turn";
    return out;
  }
  out.command = std::move(c);
  return out;
}

bool OriginAllowed(std::optional<std::string_view> origin, std::string_view host, bool tls) {
  if (!origin) return true;
  if (host.empty()) return false;
  const std::string expected = std::string(tls ? "https://" : "http://") + std::string(host);
  return *origin == expected;
}

TokenBucket::TokenBucket(double rate_per_s, double burst, Clock::time_point now)
    : rate_per_s_(rate_per_s), burst_(burst), tokens_(burst), last_(now) {}

bool TokenBucket::Take(Clock::time_point now) {
  const double elapsed_s = std::chrono::duration<double>(now - last_).count();
  if (elapsed_s > 0) {
    tokens_ = std::min(burst_, tokens_ + elapsed_s * rate_per_s_);
    last_ = now;
  }
  if (tokens_ < 1.0) return false;
  tokens_ -= 1.0;
  return true;
}

bool TokenBucket::Full(Clock::time_point now) const {
  const double elapsed_s = std::chrono::duration<double>(now - last_).count();
  return tokens_ + std::max(0.0, elapsed_s) * rate_per_s_ >= burst_;
}

int TokenBucket::SecondsToNextToken(Clock::time_point now) const {
  const double elapsed_s = std::max(0.0, std::chrono::duration<double>(now - last_).count());
  const double missing = 1.0 - std::min(burst_, tokens_ + elapsed_s * rate_per_s_);
  return std::max(1, static_cast<int>(std::ceil(missing / rate_per_s_)));
}

RateLimiter::RateLimiter(double rate_per_s, double burst, std::size_t max_addresses)
    : rate_per_s_(rate_per_s), burst_(burst), max_addresses_(max_addresses) {}

bool RateLimiter::Allow(const std::string& address, TokenBucket::Clock::time_point now) {
  auto it = buckets_.find(address);
  if (it == buckets_.end()) {
    if (buckets_.size() >= max_addresses_) {
      std::erase_if(buckets_, [now](const auto& entry) { return entry.second.Full(now); });
      if (buckets_.size() >= max_addresses_) return false;
    }
    it = buckets_.emplace(address, TokenBucket(rate_per_s_, burst_, now)).first;
  }
  return it->second.Take(now);
}

int RateLimiter::RetryAfterS(const std::string& address, TokenBucket::Clock::time_point now) const {
  const auto it = buckets_.find(address);
  // An address refused for a full table: a bucket is forgotten once it is full again.
  if (it == buckets_.end()) return std::max(1, static_cast<int>(std::ceil(burst_ / rate_per_s_)));
  return it->second.SecondsToNextToken(now);
}

}  // namespace handshare::web_console
