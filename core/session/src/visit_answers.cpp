#include "handshare/session/visit_answers.hpp"
#include "handshare/session/visit_answers_message.hpp"

namespace handshare::session {

const char* ToString(VisitQuestion question) noexcept {
  switch (question) {
    case VisitQuestion::kEase: return "ease";
    case VisitQuestion::kNaturalness: return "naturalness";
    case VisitQuestion::kSatisfaction: return "satisfaction";
  }
  return "?";
}

std::optional<VisitQuestion> VisitQuestionFromString(std::string_view text) noexcept {
  for (VisitQuestion q : {VisitQuestion::kEase, VisitQuestion::kNaturalness, VisitQuestion::kSatisfaction}) {
    if (text == ToString(q)) return q;
  }
  return {};
}

const char* ToString(scene::ControlType kind) noexcept {
  switch (kind) {
    case scene::ControlType::kButton: return "button";
    case scene::ControlType::kArrow: return "arrow";
    case scene::ControlType::kLever: return "lever";
    case scene::ControlType::kBook: return "book";
  }
  return "?";
}

std::optional<scene::ControlType> ControlTypeFromString(std::string_view text) noexcept {
  for (scene::ControlType k : {scene::ControlType::kButton, scene::ControlType::kArrow, scene::ControlType::kLever,
                               scene::ControlType::kBook}) {
    if (text == ToString(k)) return k;
  }
  return {};
}

msg::VisitAnswers ToMessage(const VisitAnswers& answers, const std::string& session, const std::string& user,
                            std::uint64_t stamp_ns) {
  msg::VisitAnswers m;
  m.session(session);
  m.user(user);
  m.visitor(answers.visitor);
  for (std::size_t k = 0; k < kVisitControlKinds; ++k) {
    for (std::size_t q = 0; q < kVisitQuestions; ++q) m.scores()[k][q] = answers.scores[k][q];
  }
  m.stamp_ns(stamp_ns);
  return m;
}

VisitAnswers FromMessage(const msg::VisitAnswers& sample) {
  VisitAnswers a;
  a.visitor = sample.visitor().to_string();
  for (std::size_t k = 0; k < kVisitControlKinds; ++k) {
    for (std::size_t q = 0; q < kVisitQuestions; ++q) a.scores[k][q] = sample.scores()[k][q];
  }
  return a;
}

}  // namespace handshare::session
