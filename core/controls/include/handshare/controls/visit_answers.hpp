#pragma once
/// A visitor's questionnaire at the end of a turn (the paper's section 1.7.1, Fig. 16 and
/// Table 3): for each kind of control (scene::ControlType: button, arrow, lever, book), ease of
/// use in selecting and moving between scenes, naturalness of its manipulation and satisfaction
/// with it, each on the paper's 1-7 scale. The web console sends them, the world server stores
/// them in the session log, session_report summarises them. No DDS: the sample's mapping is
/// handshare/session/visit_answers_message.hpp's. Not real-time.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "handshare/scene/scene.hpp"

namespace handshare::controls {

inline constexpr std::size_t kVisitControlKinds = 4;  ///< scene::ControlType's kinds
inline constexpr std::size_t kVisitQuestions = 3;
inline constexpr int kMinScore = 1;  ///< the paper's scale
inline constexpr int kMaxScore = 7;
static_assert(static_cast<std::size_t>(scene::ControlType::kBook) + 1 == kVisitControlKinds,
              "a kind of control without a row in the questionnaire");

enum class VisitQuestion { kEase, kNaturalness, kSatisfaction };

/// "ease", "naturalness", "satisfaction": the names in the page's JSON, the log and the report.
const char* ToString(VisitQuestion question) noexcept;
std::optional<VisitQuestion> VisitQuestionFromString(std::string_view text) noexcept;
/// "button", "arrow", "lever", "book".
const char* ToString(scene::ControlType kind) noexcept;
std::optional<scene::ControlType> ControlTypeFromString(std::string_view text) noexcept;

struct VisitAnswers {
  std::string visitor;  ///< whose turn (a haptic node's user)
  /// [kind][question], kMinScore..kMaxScore; 0: not answered (a kind the visitor did not use).
  std::array<std::array<std::uint8_t, kVisitQuestions>, kVisitControlKinds> scores{};
  std::uint8_t& at(scene::ControlType kind, VisitQuestion q) {
    return scores[static_cast<std::size_t>(kind)][static_cast<std::size_t>(q)];
  }
  std::uint8_t at(scene::ControlType kind, VisitQuestion q) const {
    return scores[static_cast<std::size_t>(kind)][static_cast<std::size_t>(q)];
  }
};

}  // namespace handshare::controls
