#include "handshare/session/visit_answers_message.hpp"

namespace handshare::session {

msg::VisitAnswers ToMessage(const controls::VisitAnswers& answers, const std::string& session, const std::string& user,
                            std::uint64_t stamp_ns) {
  msg::VisitAnswers m;
  m.session(session);
  m.user(user);
  m.visitor(answers.visitor);
  for (std::size_t k = 0; k < controls::kVisitControlKinds; ++k) {
    for (std::size_t q = 0; q < controls::kVisitQuestions; ++q) m.scores()[k][q] = answers.scores[k][q];
  }
  m.stamp_ns(stamp_ns);
  return m;
}

controls::VisitAnswers FromMessage(const msg::VisitAnswers& sample) {
  controls::VisitAnswers a;
  a.visitor = sample.visitor().to_string();
  for (std::size_t k = 0; k < controls::kVisitControlKinds; ++k) {
    for (std::size_t q = 0; q < controls::kVisitQuestions; ++q) a.scores[k][q] = sample.scores()[k][q];
  }
  return a;
}

}  // namespace handshare::session
