#include "handshare/controls/visit_answers.hpp"

namespace handshare::controls {

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

}  // namespace handshare::controls
