// A visitor's questionnaire at the DDS boundary: the sample the console writes is the answers
// the world server takes, every kind and question in its place; and the names the page, the log
// and the report use.
#include "handshare/session/visit_answers_message.hpp"

#include <gtest/gtest.h>

namespace handshare::session {
namespace {

using controls::VisitQuestion;
using scene::ControlType;

TEST(VisitAnswers, TheSampleCarriesEveryScoreInItsPlace) {
  controls::VisitAnswers a;
  a.visitor = "alice";
  a.at(ControlType::kButton, VisitQuestion::kEase) = 1;
  a.at(ControlType::kArrow, VisitQuestion::kNaturalness) = 2;
  a.at(ControlType::kLever, VisitQuestion::kSatisfaction) = 6;
  a.at(ControlType::kBook, VisitQuestion::kEase) = 7;
  const msg::VisitAnswers m = ToMessage(a, "museum", "web-console", 42);
  EXPECT_EQ(m.session().to_string(), "museum");
  EXPECT_EQ(m.user().to_string(), "web-console");
  EXPECT_EQ(m.visitor().to_string(), "alice");
  EXPECT_EQ(m.stamp_ns(), 42u);
  // The IDL's order: [kind: button, arrow, lever, book][ease, naturalness, satisfaction].
  EXPECT_EQ(m.scores()[0][0], 1);
  EXPECT_EQ(m.scores()[1][1], 2);
  EXPECT_EQ(m.scores()[2][2], 6);
  EXPECT_EQ(m.scores()[3][0], 7);
  EXPECT_EQ(m.scores()[3][1], 0);  // not answered
  const controls::VisitAnswers back = FromMessage(m);
  EXPECT_EQ(back.visitor, "alice");
  EXPECT_EQ(back.scores, a.scores);
}

TEST(VisitAnswers, NamesGoBothWays) {
  for (ControlType k : {ControlType::kButton, ControlType::kArrow, ControlType::kLever, ControlType::kBook}) {
    EXPECT_EQ(controls::ControlTypeFromString(controls::ToString(k)), k);
  }
  for (VisitQuestion q : {VisitQuestion::kEase, VisitQuestion::kNaturalness, VisitQuestion::kSatisfaction}) {
    EXPECT_EQ(controls::VisitQuestionFromString(controls::ToString(q)), q);
  }
  EXPECT_STREQ(controls::ToString(ControlType::kBook), "book");
  EXPECT_STREQ(controls::ToString(VisitQuestion::kNaturalness), "naturalness");
  EXPECT_FALSE(controls::ControlTypeFromString("Button"));
  EXPECT_FALSE(controls::VisitQuestionFromString(""));
}

}  // namespace
}  // namespace handshare::session
