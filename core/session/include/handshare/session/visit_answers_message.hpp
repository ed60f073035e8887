#pragma once
/// A visitor's questionnaire at the DDS boundary: the one place where controls::VisitAnswers and
/// msg::VisitAnswers are mapped onto each other (the web console sends, the world server takes).
/// Not real-time.
#include <cstdint>
#include <string>

#include "handshare/dds/messages.hpp"
#include "handshare/controls/visit_answers.hpp"

namespace handshare::session {

static_assert(controls::kVisitControlKinds == static_cast<std::size_t>(msg::kVisitControlKinds),
              "handshare.idl kVisitControlKinds != controls::kVisitControlKinds");
static_assert(controls::kVisitQuestions == static_cast<std::size_t>(msg::kVisitQuestions),
              "handshare.idl kVisitQuestions != controls::kVisitQuestions");

/// The sample the web console sends in its own name (`user`).
msg::VisitAnswers ToMessage(const controls::VisitAnswers& answers, const std::string& session, const std::string& user,
                            std::uint64_t stamp_ns);
/// The answers of a sample that dds::CheckVisitAnswers accepted.
controls::VisitAnswers FromMessage(const msg::VisitAnswers& sample);

}  // namespace handshare::session
