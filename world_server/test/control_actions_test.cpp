// The control actions over the scene: every kind of action a control can take, without DDS.
#include "handshare/world_server/control_actions.hpp"

#include <gtest/gtest.h>

#include <map>
#include <stdexcept>

#include "test_support.hpp"

namespace handshare::server {
namespace {

using controls::EventKind;
using testing::Control;
using testing::Msg;
using testing::World;

// The start menu and two worlds, the way the scene files build them.
class ControlActions : public ::testing::Test {
 protected:
  ControlActions() {
    worlds_["solar_system"] = World("solar_system", 1.62);
    worlds_["dinosaur"] = World("dinosaur", 9.81);
    scene::Scene& moon = worlds_["solar_system"];
    auto lever = Control("lever", scene::ControlType::kLever);
    scene::Action mars;
    mars.set_gravity = true;
    mars.gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -3.71);
    mars.title = "Mars";
    mars.messages = {Msg("en", "Now lift it on Mars.")};
    scene::Action back;
    back.set_gravity = true;
    back.gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -1.62);
    back.title = "Moon";
    lever.detent_actions = {back, mars};
    moon.controls.push_back(lever);
    auto home = Control("arrow_home", scene::ControlType::kArrow);
    home.action.goto_scene = "start_menu";
    moon.controls.push_back(home);

    menu_ = World("start_menu", 9.81);
    auto button = Control("button_dino", scene::ControlType::kButton);
    button.action.goto_scene = "dinosaur";
    menu_.controls.push_back(button);
    auto book = Control("book_solar", scene::ControlType::kBook);
    book.action.goto_scene = "solar_system";
    scene::Action page1;
    page1.messages = {Msg("en", "Planets."), Msg("ja", "惑星。")};
    scene::Action page2;
    page2.goto_scene = "dinosaur";
    book.page_actions = {scene::Action{}, page1, page2};
    menu_.controls.push_back(book);
    auto broken = Control("button_nowhere", scene::ControlType::kButton);
    broken.action.goto_scene = "atlantis";
    menu_.controls.push_back(broken);
    worlds_["start_menu"] = menu_;
  }

  SceneLoader Loader() {
    return [this](const std::string& name) {
      ++loads_;
      const auto it = worlds_.find(name);
      if (it == worlds_.end()) throw std::runtime_error("unknown scene '" + name + "'");
      return it->second;
    };
  }

  std::map<std::string, scene::Scene> worlds_;
  scene::Scene menu_;
  int loads_ = 0;
};

TEST_F(ControlActions, AButtonPressGoesToItsWorldAndShowsThatWorldsBoard) {
  scene::Scene s = menu_;
  const ControlOutcome out = ApplyControlAction(s, {"button_dino", EventKind::kPressed, -1, "alice"}, Loader());
  EXPECT_TRUE(out.taken);
  EXPECT_TRUE(out.world_changed);
  EXPECT_TRUE(out.revised);
  EXPECT_FALSE(out.gravity_changed);  // a new world is built anyway
  EXPECT_EQ(s.name, "dinosaur");
  ASSERT_EQ(out.boards.size(), 1u);
  EXPECT_EQ(out.boards[0].size(), 2u);  // every language of the scene
  EXPECT_EQ(out.boards[0][0].text, "welcome to dinosaur");
  ASSERT_FALSE(out.notes.empty());
  EXPECT_NE(out.notes[0].find("control button_dino by alice: scene 'dinosaur'"), std::string::npos);
}

TEST_F(ControlActions, AnArrowPressGoesToItsWorld) {
  scene::Scene s = worlds_["solar_system"];
  const ControlOutcome out = ApplyControlAction(s, {"arrow_home", EventKind::kPressed, -1, "bob"}, Loader());
  EXPECT_TRUE(out.world_changed);
  EXPECT_EQ(loads_, 1);
  EXPECT_EQ(s.name, "start_menu");
}

TEST_F(ControlActions, ReleasesAndMissesTakeNoAction) {
  for (EventKind k : {EventKind::kReleased, EventKind::kMissed}) {
    scene::Scene s = menu_;
    const ControlOutcome out = ApplyControlAction(s, {"button_dino", k, -1, "alice"}, Loader());
    EXPECT_FALSE(out.taken) << controls::ToString(k);
    EXPECT_EQ(s.name, "start_menu");
    EXPECT_TRUE(out.boards.empty());
  }
  EXPECT_EQ(loads_, 0);
}

TEST_F(ControlActions, AButtonIsNotOpenedAndABookIsNotPressed) {
  scene::Scene s = menu_;
  EXPECT_FALSE(ApplyControlAction(s, {"button_dino", EventKind::kOpened, -1, "a"}, Loader()).taken);
  EXPECT_FALSE(ApplyControlAction(s, {"book_solar", EventKind::kPressed, -1, "a"}, Loader()).taken);
  EXPECT_EQ(s.name, "start_menu");
}

TEST_F(ControlActions, OpeningABookTakesItsAction) {
  scene::Scene s = menu_;
  const ControlOutcome out = ApplyControlAction(s, {"book_solar", EventKind::kOpened, 0, "alice"}, Loader());
  EXPECT_TRUE(out.world_changed);
  EXPECT_EQ(s.name, "solar_system");
}

TEST_F(ControlActions, ABooksPagesTakeTheirOwnActions) {
  scene::Scene s = menu_;
  // Page 0 has an empty action: nothing happens.
  EXPECT_FALSE(ApplyControlAction(s, {"book_solar", EventKind::kPageTurned, 0, "alice"}, Loader()).taken);
  // Page 1 shows its text on the board and stays in the menu.
  ControlOutcome out = ApplyControlAction(s, {"book_solar", EventKind::kPageTurned, 1, "alice"}, Loader());
  EXPECT_TRUE(out.taken);
  EXPECT_FALSE(out.revised);
  EXPECT_EQ(s.name, "start_menu");
  ASSERT_EQ(out.boards.size(), 1u);
  EXPECT_EQ(out.boards[0][0].text, "Planets.");
  EXPECT_EQ(out.boards[0][1].language, "ja");
  // Page 2 goes to a world.
  out = ApplyControlAction(s, {"book_solar", EventKind::kPageTurned, 2, "alice"}, Loader());
  EXPECT_TRUE(out.world_changed);
  EXPECT_EQ(s.name, "dinosaur");
}

TEST_F(ControlActions, ABookWithoutItsOwnActionOpensAtPageOne) {
  scene::Scene s = menu_;
  s.controls[1].action = scene::Action{};
  s.controls[1].page_actions[0].title = "Page one";
  const ControlOutcome out = ApplyControlAction(s, {"book_solar", EventKind::kOpened, 0, "alice"}, Loader());
  EXPECT_TRUE(out.taken);
  EXPECT_FALSE(out.world_changed);
  EXPECT_EQ(s.name, "start_menu");
  EXPECT_EQ(s.title, "Page one");
}

// The project's start menu: a book opens at page 1 (its board message, no other world), and
// page 2 takes the book's world. Every book alike.
TEST(ControlActionsOfTheScenes, OpenABookTurnToPageTwoAndGoToItsWorld) {
  for (const char* world : {"solar_system", "dinosaur", "microscopic"}) {
    scene::Scene s = LoadWorld("start_menu");
    const std::string book = std::string("book_") + world;
    std::vector<ControlStateRecord> states = InitialControlStates(s);
    const ControlInput open{book, EventKind::kOpened, 0, "alice"};
    ASSERT_NE(UpdateControlState(states, open), nullptr);
    ControlOutcome out = ApplyControlAction(s, open, LoadWorld);
    EXPECT_TRUE(out.taken) << world;
    EXPECT_FALSE(out.world_changed) << world;
    EXPECT_EQ(s.name, "start_menu");
    ASSERT_EQ(out.boards.size(), 1U) << world;
    EXPECT_EQ(out.boards[0].size(), 2U) << world << ": English and Japanese";
    const ControlInput turn{book, EventKind::kPageTurned, 1, "alice"};
    const ControlStateRecord* page = UpdateControlState(states, turn);
    ASSERT_NE(page, nullptr);
    EXPECT_EQ(page->index, 1);
    EXPECT_TRUE(page->engaged);
    out = ApplyControlAction(s, turn, LoadWorld);
    EXPECT_TRUE(out.world_changed) << world;
    EXPECT_EQ(s.name, world);
    ASSERT_FALSE(out.notes.empty());
    EXPECT_NE(out.notes[0].find("control " + book + " by alice: scene '" + world + "'"), std::string::npos) << out.notes[0];
  }
}

TEST_F(ControlActions, APageOrDetentOutsideTheListsTakesNothing) {
  scene::Scene s = menu_;
  for (std::int32_t page : {-1, 3, 99}) {
    EXPECT_FALSE(ApplyControlAction(s, {"book_solar", EventKind::kPageTurned, page, "a"}, Loader()).taken) << page;
  }
  scene::Scene moon = worlds_["solar_system"];
  EXPECT_FALSE(ApplyControlAction(moon, {"lever", EventKind::kMoved, 2, "a"}, Loader()).taken);
  EXPECT_FALSE(ApplyControlAction(moon, {"lever", EventKind::kMoved, -1, "a"}, Loader()).taken);
}

TEST_F(ControlActions, ALeverDetentChangesGravityAndTitleInTheSameWorld) {
  scene::Scene s = worlds_["solar_system"];
  ControlOutcome out = ApplyControlAction(s, {"lever", EventKind::kMoved, 1, "alice"}, Loader());
  EXPECT_TRUE(out.taken);
  EXPECT_FALSE(out.world_changed);
  EXPECT_TRUE(out.revised);
  EXPECT_TRUE(out.gravity_changed);
  EXPECT_EQ(s.name, "solar_system");
  EXPECT_DOUBLE_EQ(s.gravity_W_m_per_s2.z(), -3.71);
  EXPECT_EQ(s.title, "Mars");
  ASSERT_EQ(out.boards.size(), 1u);
  EXPECT_EQ(out.boards[0][0].text, "Now lift it on Mars.");
  ASSERT_FALSE(out.notes.empty());
  EXPECT_NE(out.notes.back().find("gravity -3.71 m/s^2, 'Mars'"), std::string::npos);
  // And back to the Moon.
  out = ApplyControlAction(s, {"lever", EventKind::kMoved, 0, "alice"}, Loader());
  EXPECT_TRUE(out.gravity_changed);
  EXPECT_DOUBLE_EQ(s.gravity_W_m_per_s2.z(), -1.62);
  EXPECT_TRUE(out.boards.empty());
  EXPECT_EQ(loads_, 0);
}

TEST_F(ControlActions, AControlOfAWorldAlreadyLeftTakesNothing) {
  scene::Scene s = worlds_["dinosaur"];
  EXPECT_EQ(ActionOf(s, {"button_dino", EventKind::kPressed, -1, "a"}), nullptr);
  EXPECT_FALSE(ApplyControlAction(s, {"button_dino", EventKind::kPressed, -1, "a"}, Loader()).taken);
  EXPECT_EQ(s.name, "dinosaur");
}

TEST_F(ControlActions, AWorldThatCannotBeLoadedLeavesTheSceneAsItWasAndSaysWhy) {
  scene::Scene s = menu_;
  const ControlOutcome out = ApplyControlAction(s, {"button_nowhere", EventKind::kPressed, -1, "carol"}, Loader());
  EXPECT_TRUE(out.taken);
  EXPECT_FALSE(out.revised);
  EXPECT_FALSE(out.world_changed);
  EXPECT_EQ(s.name, "start_menu");
  EXPECT_TRUE(out.boards.empty());
  ASSERT_EQ(out.notes.size(), 1u);
  EXPECT_NE(out.notes[0].find("cannot go to 'atlantis': unknown scene 'atlantis'"), std::string::npos);
}

TEST_F(ControlActions, TheShippedStartMenuBookTakesItsPageActions) {
  // The real scene files: back at page 1 of the solar-system book (a turn back from page 2 is
  // possible only in a book whose page 2 does not leave), its bilingual text again.
  scene::Scene s = scene::LoadSceneByName("start_menu");
  const ControlInput page{"book_solar_system", EventKind::kPageTurned, 0, "a"};
  const ControlOutcome turned = ApplyControlAction(s, page, LoadWorld);
  EXPECT_TRUE(turned.taken);
  EXPECT_EQ(s.name, "start_menu");
  ASSERT_EQ(turned.boards.size(), 1u);
  ASSERT_EQ(turned.boards[0].size(), 2u);
  EXPECT_EQ(turned.boards[0][0].text, "Planets in the solar system.");
  EXPECT_EQ(turned.boards[0][1].language, "ja");
}

}  // namespace
}  // namespace handshare::server

namespace handshare::server {
namespace {

// Where the events leave each control, as the server publishes it (handshare/control_state).
TEST_F(ControlActions, ControlStatesStartAtRestAndFollowTheEvents) {
  std::vector<ControlStateRecord> moon = InitialControlStates(worlds_["solar_system"]);
  ASSERT_EQ(moon.size(), 2u);
  EXPECT_EQ(moon[0].control_id, "lever");
  EXPECT_EQ(moon[0].scene, "solar_system");
  EXPECT_EQ(moon[0].index, 0);  // a lever rests in detent 0
  EXPECT_EQ(moon[1].index, -1);
  EXPECT_FALSE(moon[1].engaged);

  // The lever into Mars' detent, and back: each a change; a repeat of the same detent is none.
  const ControlStateRecord* r = UpdateControlState(moon, {"lever", EventKind::kMoved, 1, "alice"});
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->index, 1);
  EXPECT_EQ(r->user, "alice");
  EXPECT_EQ(r->changes, 1u);
  EXPECT_EQ(UpdateControlState(moon, {"lever", EventKind::kMoved, 1, "bob"}), nullptr);
  r = UpdateControlState(moon, {"lever", EventKind::kMoved, 0, "bob"});
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->index, 0);
  EXPECT_EQ(r->changes, 2u);

  // An arrow is pressed, then released; a miss changes nothing; an unknown control is ignored.
  EXPECT_TRUE(UpdateControlState(moon, {"arrow_home", EventKind::kPressed, -1, "bob"})->engaged);
  EXPECT_EQ(UpdateControlState(moon, {"arrow_home", EventKind::kMissed, -1, "bob"}), nullptr);
  EXPECT_FALSE(UpdateControlState(moon, {"arrow_home", EventKind::kReleased, -1, "bob"})->engaged);
  EXPECT_EQ(UpdateControlState(moon, {"button_dino", EventKind::kPressed, -1, "bob"}), nullptr);
}

// A server that resumed a killed one's session does not know where the controls are: the first
// event of each is published whatever it says (the lever pushed back to detent 0, which this
// server would have taken for no change), and counts as known from then on.
TEST_F(ControlActions, AfterAResumeTheFirstEventOfAControlIsAlwaysAChange) {
  std::vector<ControlStateRecord> moon = InitialControlStates(worlds_["solar_system"], /*known=*/false);
  EXPECT_FALSE(moon[0].known);
  const ControlStateRecord* r = UpdateControlState(moon, {"lever", EventKind::kMoved, 0, "alice"});
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->index, 0);
  EXPECT_TRUE(r->known);
  EXPECT_EQ(UpdateControlState(moon, {"lever", EventKind::kMoved, 0, "alice"}), nullptr);
  EXPECT_EQ(UpdateControlState(moon, {"lever", EventKind::kMissed, -1, "alice"}), nullptr);
}

// A hand moving a control (motion reports) makes it moving at that position, for screens; at
// rest, or with a settled event, it stops moving. Motion takes no action, and a control whose
// settled state is unknown (after a resume) takes no motion until an event says where it is.
TEST_F(ControlActions, MotionReportsMoveAControlForTheScreens) {
  std::vector<ControlStateRecord> moon = InitialControlStates(worlds_["solar_system"]);
  ControlInput moving{"lever", EventKind::kMoving, 1, "alice", 0.2};
  const ControlStateRecord* r = UpdateControlState(moon, moving);
  ASSERT_NE(r, nullptr);
  EXPECT_TRUE(r->moving);
  EXPECT_DOUBLE_EQ(r->position, 0.2);
  EXPECT_EQ(r->index, 0) << "still in its detent until it settles in another";
  EXPECT_EQ(UpdateControlState(moon, moving), nullptr) << "the same position again: no change";
  moving.value = 0.35;
  ASSERT_NE(UpdateControlState(moon, moving), nullptr);
  r = UpdateControlState(moon, {"lever", EventKind::kMoved, 1, "alice"});
  ASSERT_NE(r, nullptr);
  EXPECT_FALSE(r->moving) << "settled";
  EXPECT_EQ(r->index, 1);
  EXPECT_DOUBLE_EQ(r->position, 0.0);
  ASSERT_NE(UpdateControlState(moon, {"lever", EventKind::kMoving, 1, "alice", 0.58}), nullptr);
  r = UpdateControlState(moon, {"lever", EventKind::kMoving, 0, "alice", 0.6});
  ASSERT_NE(r, nullptr);
  EXPECT_FALSE(r->moving) << "at rest";
  EXPECT_EQ(r->index, 1);

  scene::Scene s = worlds_["solar_system"];
  const ControlOutcome out = ApplyControlAction(s, {"lever", EventKind::kMoving, 1, "alice", 0.5}, Loader());
  EXPECT_FALSE(out.taken);
  EXPECT_DOUBLE_EQ(s.gravity_W_m_per_s2.z(), -1.62);

  std::vector<ControlStateRecord> resumed = InitialControlStates(worlds_["solar_system"], /*known=*/false);
  EXPECT_EQ(UpdateControlState(resumed, {"lever", EventKind::kMoving, 1, "alice", 0.2}), nullptr);
}

TEST_F(ControlActions, ABookOpensAtItsFirstPageAndTurns) {
  std::vector<ControlStateRecord> menu = InitialControlStates(menu_);
  const ControlStateRecord* r = UpdateControlState(menu, {"book_solar", EventKind::kOpened, 0, "alice"});
  ASSERT_NE(r, nullptr);
  EXPECT_TRUE(r->engaged);
  EXPECT_EQ(r->index, 0);
  r = UpdateControlState(menu, {"book_solar", EventKind::kPageTurned, 2, "alice"});
  ASSERT_NE(r, nullptr);
  EXPECT_EQ(r->index, 2);
  EXPECT_TRUE(r->engaged);
}

// What a resumed server accepts from its log (a scene file may have changed since): a lever
// only in its detents, a book shut or at one of its pages, a button or an arrow at -1.
TEST(ControlIndex, APlaceFitsOnlyWhereTheControlCanBe) {
  scene::ControlSpec lever;
  lever.type = scene::ControlType::kLever;
  lever.lever.detents = 2;
  EXPECT_TRUE(IndexFits(lever, 0));
  EXPECT_TRUE(IndexFits(lever, 1));
  EXPECT_FALSE(IndexFits(lever, 2));
  EXPECT_FALSE(IndexFits(lever, -1));
  scene::ControlSpec book;
  book.type = scene::ControlType::kBook;
  book.book.pages = 6;
  EXPECT_TRUE(IndexFits(book, -1));
  EXPECT_TRUE(IndexFits(book, 5));
  EXPECT_FALSE(IndexFits(book, 6));
  EXPECT_FALSE(IndexFits(book, -2));
  scene::ControlSpec button;
  button.type = scene::ControlType::kButton;
  EXPECT_TRUE(IndexFits(button, -1));
  EXPECT_FALSE(IndexFits(button, 0));
  scene::ControlSpec arrow;
  arrow.type = scene::ControlType::kArrow;
  EXPECT_FALSE(IndexFits(arrow, 3));
}

}  // namespace
}  // namespace handshare::server
