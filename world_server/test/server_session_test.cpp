// The world server's tick as a function from its state and inputs to domain events: inputs as
// SampleIntake would take them, events asserted, no DDS participant. The start (fresh and
// resumed from a killed server's log) goes through the same path.
#include "server_session.hpp"

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <algorithm>
#include <fstream>
#include <map>
#include <stdexcept>
#include <thread>

#include "session_log_writer.hpp"
#include "test_support.hpp"

namespace handshare::server {
namespace {

using Clock = ServerSession::Clock;
using Events = ServerSession::Events;
using controls::EventKind;
using testing::Control;
using testing::Msg;
using testing::TempDir;
using testing::World;
using testing::WriteBallScene;

// The name of an event's kind, for asserting the order of a tick's events.
std::string KindOf(const SessionEvent& e) {
  static const char* const kNames[] = {"LineSaid",       "MemberChanged",       "RosterChanged", "SceneRevised",
                                       "SceneShown",     "SessionStateChanged", "MessageSaid",   "ControlApplied",
                                       "ControlStateChanged", "WorldEntered",   "OwnershipChanged", "BodyMoved",
                                       "FieldChanged",   "SessionCheckpoint",   "TurnEnded",     "VisitAnswered",
                                       "StationReported"};
  static_assert(std::size(kNames) == std::variant_size_v<SessionEvent>);
  return kNames[e.index()];
}

std::vector<std::string> Kinds(const Events& events, bool with_lines = true) {
  std::vector<std::string> kinds;
  for (const auto& e : events) {
    if (with_lines || !std::holds_alternative<LineSaid>(e)) kinds.push_back(KindOf(e));
  }
  return kinds;
}

template <typename E>
std::vector<E> All(const Events& events) {
  std::vector<E> out;
  for (const auto& e : events) {
    if (const auto* x = std::get_if<E>(&e)) out.push_back(*x);
  }
  return out;
}

std::vector<std::string> Lines(const Events& events) {
  std::vector<std::string> lines;
  for (const auto& e : All<LineSaid>(events)) lines.push_back(e.line);
  return lines;
}

InstanceKey Key(std::uint8_t participant, std::uint8_t entity = 1) {
  InstanceKey k{};
  k[0] = participant;  // the first 12 bytes of a writer's GUID name its participant
  k[15] = entity;
  return k;
}

MemberInput Announced(const std::string& user, std::uint8_t participant, const std::string& kind = "haptic") {
  MemberInput m;
  m.kind = MemberInput::Kind::kAnnounced;
  m.instance = Key(participant, 7);
  m.writer = Key(participant);
  m.member = Member{user + "-member", user, kind, kind == "haptic" ? "sim" : "", 40 + participant};
  return m;
}

ControlEventInput Event(const std::string& control, EventKind kind, std::int32_t index, double value,
                        std::uint8_t participant = 1, const std::string& user = "alice") {
  ControlEventInput e;
  e.user = user;
  e.writer = Key(participant, 3);
  e.input = ControlInput{control, kind, index, user, value};
  e.record.unix_ns = testing::kT0;
  e.record.user = user;
  e.record.control_id = control;
  e.record.kind = kind;
  e.record.value = value;
  e.record.error_m = 0.002;
  return e;
}

// A start menu whose button opens the dinosaur world, and a solar system whose lever sets Mars'
// gravity (no objects: the models build at once).
class ServerSessionTest : public ::testing::Test {
 protected:
  ServerSessionTest() {
    scene::Scene menu = World("start_menu", 9.81);
    auto button = Control("button_dino", scene::ControlType::kButton);
    button.action.goto_scene = "dinosaur";
    menu.controls.push_back(button);
    auto book = Control("book_solar", scene::ControlType::kBook);
    book.action.goto_scene = "solar_system";
    menu.controls.push_back(book);
    worlds_["start_menu"] = menu;
    worlds_["dinosaur"] = World("dinosaur", 9.81);
    scene::Scene solar = World("solar_system", 1.62);
    auto lever = Control("lever", scene::ControlType::kLever);
    scene::Action moon;
    moon.set_gravity = true;
    moon.gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -1.62);
    scene::Action mars;
    mars.set_gravity = true;
    mars.gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -3.71);
    mars.title = "Mars";
    mars.messages = {Msg("en", "Now lift it on Mars.")};
    lever.detent_actions = {moon, mars};
    solar.controls.push_back(lever);
    worlds_["solar_system"] = solar;
  }

  ServerSessionConfig Config() {
    ServerSessionConfig c;
    c.session = "s";
    c.domain_id = 7;
    c.tick_Hz = 60.0;
    c.objects.models.cache_dir = dir_.path() / "cache";
    c.load = [this](const std::string& name) {
      const auto it = worlds_.find(name);
      if (it == worlds_.end()) throw std::runtime_error("unknown scene '" + name + "'");
      return it->second;
    };
    return c;
  }

  // Starts `session` and ticks it without inputs until its models are adopted (their loader's
  // note, "models of ... ready", is then out of the way of the ticks a test asserts).
  void StartAndWaitForModels(ServerSession& session) {
    session.Start();
    for (int i = 0; i < 2000 && !session.objects().ready(); ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      now_ += std::chrono::milliseconds(10);
      session.Tick({}, now_, 0.01);
    }
    ASSERT_TRUE(session.objects().ready());
  }

  TempDir dir_;
  std::map<std::string, scene::Scene> worlds_;
  Clock::time_point now_ = Clock::now();
};

TEST_F(ServerSessionTest, AFreshStartRevisesTheSceneShowsItsWorldPutsItsControlsAtRestAndSaysItsBoard) {
  ServerSession session(Config(), worlds_["start_menu"]);
  const Events events = session.Start();
  EXPECT_EQ(Kinds(events), (std::vector<std::string>{"SceneRevised", "SessionStateChanged", "RosterChanged", "LineSaid",
                                                     "SceneShown", "WorldEntered", "ControlStateChanged",
                                                     "ControlStateChanged", "MessageSaid", "SessionStateChanged"}));
  const auto revised = All<SceneRevised>(events);
  EXPECT_EQ(revised[0].scene.name, "start_menu");
  EXPECT_EQ(revised[0].revision, 1u);
  EXPECT_EQ(revised[0].tick_Hz, 60.0);
  EXPECT_EQ(Lines(events)[0], "session 's' on domain 7: scene 'start_menu' (0 objects)");
  const auto said = All<MessageSaid>(events);
  EXPECT_EQ(said[0].message_id, 1u);
  EXPECT_EQ(said[0].messages[0].text, "welcome to start_menu");
  // Where the session is, once the board is said: what a restart resumes from.
  const auto states = All<SessionStateChanged>(events);
  EXPECT_EQ(states.back().state.scene, "start_menu");
  EXPECT_EQ(states.back().state.revision, 1u);
  EXPECT_EQ(states.back().state.message_id, 1u);
  EXPECT_EQ(states.back().state.board.size(), 2u);
  for (const auto& c : All<ControlStateChanged>(events)) {
    EXPECT_TRUE(c.settled);
    EXPECT_TRUE(c.record.known);
  }
}

TEST_F(ServerSessionTest, AMemberJoiningGivesMemberJoinedAndTheRosterAndLeavingGivesMemberLeft) {
  ServerSession session(Config(), worlds_["start_menu"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.members.push_back(Announced("alice", 1));
  Events events = session.Tick(in, now_, 1.0 / 60);
  EXPECT_EQ(Kinds(events), (std::vector<std::string>{"RosterChanged", "MemberChanged"}));
  const auto joined = All<MemberChanged>(events);
  EXPECT_EQ(joined[0].event.change, MemberChange::kJoined);
  EXPECT_EQ(joined[0].event.member.user, "alice");
  EXPECT_EQ(joined[0].present, 1u);
  EXPECT_EQ(All<RosterChanged>(events)[0].member_ids, std::vector<std::string>{"alice-member"});

  // The same announcement again changes nothing; a dispose is a clean leave.
  events = session.Tick(in, now_ + std::chrono::milliseconds(17), 1.0 / 60);
  EXPECT_TRUE(All<MemberChanged>(events).empty());
  in.members[0].kind = MemberInput::Kind::kDisposed;
  events = session.Tick(in, now_ + std::chrono::milliseconds(34), 1.0 / 60);
  const auto left = All<MemberChanged>(events);
  ASSERT_EQ(left.size(), 1u);
  EXPECT_EQ(left[0].event.change, MemberChange::kLeft);
  EXPECT_EQ(left[0].present, 0u);
  EXPECT_TRUE(All<RosterChanged>(events).at(0).member_ids.empty());
}

// --visit-minutes: a haptic member's turn ends that long after its join, once: TurnEnded, then
// the board's message in English and Japanese under the next number; a screen takes no turn.
TEST_F(ServerSessionTest, AVisitorsTurnEndsOnceAfterItsLengthAndTheBoardSaysSo) {
  ServerSessionConfig config = Config();
  config.visit_turn = std::chrono::seconds(3);  // 0.05 minutes
  ServerSession session(config, worlds_["start_menu"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.members.push_back(Announced("alice", 1));
  in.members.push_back(Announced("screen", 2, "graphics"));
  const Clock::time_point joined = now_;
  session.Tick(in, joined, 1.0 / 60);
  Events events = session.Tick({}, joined + std::chrono::milliseconds(2999), 1.0 / 60);
  EXPECT_TRUE(All<TurnEnded>(events).empty());
  events = session.Tick({}, joined + std::chrono::seconds(3), 1.0 / 60);
  EXPECT_EQ(Kinds(events), (std::vector<std::string>{"TurnEnded", "MessageSaid", "SessionStateChanged",
                                                     "SessionCheckpoint"}));
  const auto ended = All<TurnEnded>(events);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].member.user, "alice");
  EXPECT_EQ(ended[0].turn, std::chrono::seconds(3));
  EXPECT_DOUBLE_EQ(ended[0].minutes, 0.05);
  const auto said = All<MessageSaid>(events);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0].message_id, 2u);  // the start's board was #1
  ASSERT_EQ(said[0].messages.size(), 2u);
  EXPECT_EQ(said[0].messages[0].language, "en");
  EXPECT_EQ(said[0].messages[0].text, "Thank you, alice: your 0.05 minutes are over.");
  EXPECT_EQ(said[0].messages[1].language, "ja");
  EXPECT_NE(said[0].messages[1].text.find("alice"), std::string::npos);
  EXPECT_EQ(All<SessionStateChanged>(events)[0].state.board.size(), 2u);  // a restart shows it again
  // Once: later ticks say nothing more.
  EXPECT_TRUE(All<TurnEnded>(session.Tick({}, joined + std::chrono::seconds(60), 1.0 / 60)).empty());
}

TEST_F(ServerSessionTest, TurnsNeverEndWithoutALengthAndEndWithTheMemberLeaving) {
  ServerSession off(Config(), worlds_["start_menu"]);  // visit_turn 0: off
  StartAndWaitForModels(off);
  TickInputs in;
  in.members.push_back(Announced("alice", 1));
  off.Tick(in, now_, 1.0 / 60);
  EXPECT_TRUE(All<TurnEnded>(off.Tick({}, now_ + std::chrono::hours(2), 1.0 / 60)).empty());

  ServerSessionConfig config = Config();
  config.visit_turn = std::chrono::seconds(3);
  ServerSession session(config, worlds_["start_menu"]);
  StartAndWaitForModels(session);
  session.Tick(in, now_, 1.0 / 60);
  in.members[0].kind = MemberInput::Kind::kDisposed;
  session.Tick(in, now_ + std::chrono::seconds(1), 1.0 / 60);  // alice leaves before her turn's end
  EXPECT_TRUE(All<TurnEnded>(session.Tick({}, now_ + std::chrono::seconds(5), 1.0 / 60)).empty());
}

// A questionnaire from the console: VisitAnswered and a checkpoint (committed at once); a
// refused sample is counted and said, and gives nothing to the log.
TEST_F(ServerSessionTest, AVisitorsAnswersGoToTheLogAndARefusedSampleDoesNot) {
  ServerSession session(Config(), worlds_["start_menu"]);
  StartAndWaitForModels(session);
  TickInputs in;
  VisitAnswersInput v;
  v.user = "web-console";
  v.writer = Key(5, 4);
  v.answers.visitor = "alice";
  v.answers.at(scene::ControlType::kBook, controls::VisitQuestion::kEase) = 6;
  in.visits.push_back(v);
  VisitAnswersInput bad = v;
  bad.refused = "scores[0][0] 9 is not 0..7";
  in.visits.push_back(bad);
  const Events events = session.Tick(in, now_, 1.0 / 60);
  const auto answered = All<VisitAnswered>(events);
  ASSERT_EQ(answered.size(), 1u);
  EXPECT_EQ(answered[0].sent_by, "web-console");
  EXPECT_EQ(answered[0].answers.visitor, "alice");
  EXPECT_EQ(answered[0].answers.at(scene::ControlType::kBook, controls::VisitQuestion::kEase), 6);
  EXPECT_EQ(All<SessionCheckpoint>(events).size(), 1u);
  EXPECT_EQ(session.dropped().total(), 1u);
}

OperatorCommandInput Command(controls::OperatorAction action, const std::string& world = "",
                             const std::string& visitor = "") {
  OperatorCommandInput c;
  c.user = "web-console";
  c.writer = Key(5, 6);
  c.command = controls::OperatorCommand{action, world, visitor};
  return c;
}

// The operator's "send the session to a world" reaches a world no control of the current one
// links to (the start menu links only the dinosaurs and the solar system's book; from the
// dinosaurs nothing leads to the solar system), through the same path as a control's action;
// a world that cannot be loaded changes nothing and is said; a refused sample is counted.
TEST_F(ServerSessionTest, TheOperatorSendsTheSessionToAWorldNoControlLinks) {
  ServerSession session(Config(), worlds_["dinosaur"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.members.push_back(Announced("web-console", 5, "graphics"));
  session.Tick(in, now_, 1.0 / 60);
  in = {};
  in.commands.push_back(Command(controls::OperatorAction::kGoToWorld, "solar_system"));
  Events events = session.Tick(in, now_ + std::chrono::milliseconds(17), 1.0 / 60);
  EXPECT_EQ(Kinds(events, /*with_lines=*/false),
            (std::vector<std::string>{"WorldEntered", "ControlStateChanged", "SceneRevised", "SessionStateChanged",
                                      "SceneShown", "MessageSaid", "SessionStateChanged", "SessionCheckpoint"}));
  EXPECT_EQ(session.scene().name, "solar_system");
  EXPECT_EQ(All<SceneRevised>(events)[0].revision, 2u);
  ASSERT_FALSE(Lines(events).empty());
  EXPECT_EQ(Lines(events)[0], "operator command go_to_world by web-console: scene 'solar_system' (revision 2)");
  EXPECT_TRUE(All<ControlApplied>(events).empty());  // not a control's event: not in Table 4

  in = {};
  in.commands.push_back(Command(controls::OperatorAction::kGoToWorld, "atlantis"));
  OperatorCommandInput refused = Command(controls::OperatorAction::kGoToWorld, "dinosaur");
  refused.refused = "world 'Dinosaur' is not a world's name ([a-z0-9_])";
  in.commands.push_back(refused);
  OperatorCommandInput impostor = Command(controls::OperatorAction::kGoToWorld, "dinosaur");
  impostor.writer = Key(9, 6);  // another participant in the console's name
  in.commands.push_back(impostor);
  events = session.Tick(in, now_ + std::chrono::milliseconds(34), 1.0 / 60);
  EXPECT_EQ(session.scene().name, "solar_system");
  EXPECT_TRUE(All<SceneRevised>(events).empty());
  // (The solar system's models may say they are ready in this tick, before the command's line.)
  const auto lines = Lines(events);
  EXPECT_TRUE(std::any_of(lines.begin(), lines.end(),
                          [](const std::string& l) { return l.find("cannot go to 'atlantis'") != std::string::npos; }))
      << ::testing::PrintToString(lines);
  EXPECT_EQ(session.dropped().total(), 2u);
}

// "Restart the tour": the world the session started in again, from its first message with
// its controls at rest, also when the session is there; every present visitor's turn ended
// (by the operator, no thank-you on the board: the tour's first message is shown) and begun
// again, so it ends its full length after the restart.
TEST_F(ServerSessionTest, RestartingTheTourGoesToItsFirstWorldAndStartsEveryVisitorsTurnAgain) {
  ServerSessionConfig config = Config();
  config.visit_turn = std::chrono::seconds(3);
  config.tour_start = "start_menu";
  ServerSession session(config, worlds_["start_menu"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.members.push_back(Announced("alice", 1));
  in.members.push_back(Announced("web-console", 5, "graphics"));
  const Clock::time_point joined = now_;
  session.Tick(in, joined, 1.0 / 60);
  in = {};
  in.controls.push_back(Event("button_dino", EventKind::kPressed, -1, 1.0));
  session.Tick(in, joined + std::chrono::seconds(1), 1.0 / 60);
  ASSERT_EQ(session.scene().name, "dinosaur");

  in = {};
  in.commands.push_back(Command(controls::OperatorAction::kRestartTour));
  const Clock::time_point restarted = joined + std::chrono::seconds(2);
  Events events = session.Tick(in, restarted, 1.0 / 60);
  EXPECT_EQ(session.scene().name, "start_menu");
  EXPECT_EQ(All<WorldEntered>(events).at(0).scene, "start_menu");
  const auto ended = All<TurnEnded>(events);
  ASSERT_EQ(ended.size(), 1u);
  EXPECT_EQ(ended[0].member.user, "alice");
  EXPECT_EQ(ended[0].turn, std::chrono::seconds(2));
  EXPECT_EQ(ended[0].ended_by, "web-console");
  const auto said = All<MessageSaid>(events);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_EQ(said[0].messages[0].text, "welcome to start_menu");
  // Her new turn runs 3 s from the restart: not over at the first one's end.
  EXPECT_TRUE(All<TurnEnded>(session.Tick({}, joined + std::chrono::seconds(4), 1.0 / 60)).empty());
  EXPECT_EQ(All<TurnEnded>(session.Tick({}, restarted + std::chrono::seconds(3), 1.0 / 60)).size(), 1u);

  // Restarting in the first world still begins it afresh (a new revision, its first message).
  in = {};
  in.commands.push_back(Command(controls::OperatorAction::kRestartTour));
  events = session.Tick(in, restarted + std::chrono::seconds(4), 1.0 / 60);
  EXPECT_EQ(All<SceneRevised>(events).size(), 1u);
  EXPECT_EQ(All<MessageSaid>(events).at(0).messages[0].text, "welcome to start_menu");
  // Her turn had ended by itself, yet the restart gives her a new one.
  EXPECT_TRUE(All<TurnEnded>(events).empty());
  EXPECT_EQ(All<TurnEnded>(session.Tick({}, restarted + std::chrono::seconds(7), 1.0 / 60)).size(), 1u);
}

// "End a visitor's turn": now, once, with the board's thanks without a length, also when turns
// do not end by themselves (--visit-minutes 0); a visitor without an open turn is said, and
// nothing else happens.
TEST_F(ServerSessionTest, TheOperatorEndsAVisitorsTurnOnceAndTheBoardThanksThem) {
  ServerSession session(Config(), worlds_["start_menu"]);  // visit_turn 0: turns never end by themselves
  StartAndWaitForModels(session);
  TickInputs in;
  in.members.push_back(Announced("alice", 1));
  in.members.push_back(Announced("bob", 2));
  session.Tick(in, now_, 1.0 / 60);
  in = {};
  in.commands.push_back(Command(controls::OperatorAction::kEndTurn, "", "alice"));
  Events events = session.Tick(in, now_ + std::chrono::seconds(90), 1.0 / 60);
  EXPECT_EQ(Kinds(events, /*with_lines=*/false),
            (std::vector<std::string>{"TurnEnded", "MessageSaid", "SessionStateChanged", "SessionCheckpoint"}));
  const auto ended = All<TurnEnded>(events);
  EXPECT_EQ(ended.at(0).member.user, "alice");
  EXPECT_EQ(ended.at(0).turn, std::chrono::seconds(90));
  EXPECT_EQ(ended.at(0).ended_by, "web-console");
  EXPECT_EQ(All<MessageSaid>(events).at(0).messages.at(0).text, "Thank you, alice: your turn is over.");

  in = {};
  in.commands.push_back(Command(controls::OperatorAction::kEndTurn, "", "alice"));
  in.commands.push_back(Command(controls::OperatorAction::kEndTurn, "", "carol"));
  events = session.Tick(in, now_ + std::chrono::seconds(91), 1.0 / 60);
  EXPECT_TRUE(All<TurnEnded>(events).empty());
  EXPECT_TRUE(All<MessageSaid>(events).empty());
  const auto lines = Lines(events);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_NE(lines[0].find("alice has no turn to end"), std::string::npos) << lines[0];
  EXPECT_NE(lines[1].find("carol has no turn to end"), std::string::npos) << lines[1];
}

TEST_F(ServerSessionTest, AMemberWhoseWriterIsLostVanishes) {
  ServerSession session(Config(), worlds_["start_menu"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.members.push_back(Announced("alice", 1));
  session.Tick(in, now_, 1.0 / 60);
  TickInputs lost;
  lost.member_writers.push_back({Key(1), /*alive=*/false});
  const Events events = session.Tick(lost, now_ + std::chrono::milliseconds(17), 1.0 / 60);
  const auto gone = All<MemberChanged>(events);
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].event.change, MemberChange::kLost);
  EXPECT_EQ(gone[0].event.member.user, "alice");
}

TEST_F(ServerSessionTest, AControlEventThatOpensAnotherWorldGivesControlAppliedSceneRevisedAndMessageSaid) {
  ServerSession session(Config(), worlds_["start_menu"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.controls.push_back(Event("button_dino", EventKind::kPressed, -1, 1.0));
  const Events events = session.Tick(in, now_, 1.0 / 60);
  EXPECT_EQ(Kinds(events, /*with_lines=*/false),
            (std::vector<std::string>{"ControlApplied", "ControlStateChanged", "WorldEntered", "SceneRevised",
                                      "SessionStateChanged", "SceneShown", "MessageSaid", "SessionStateChanged",
                                      "SessionCheckpoint"}));
  const auto applied = All<ControlApplied>(events);
  EXPECT_EQ(applied[0].record.control_id, "button_dino");
  EXPECT_EQ(applied[0].record.kind, EventKind::kPressed);
  EXPECT_EQ(applied[0].record.user, "alice");
  const auto pressed = All<ControlStateChanged>(events);
  EXPECT_EQ(pressed[0].record.control_id, "button_dino");
  EXPECT_TRUE(pressed[0].record.engaged);
  EXPECT_TRUE(pressed[0].settled);
  EXPECT_EQ(All<WorldEntered>(events)[0].scene, "dinosaur");
  const auto revised = All<SceneRevised>(events);
  EXPECT_EQ(revised[0].scene.name, "dinosaur");
  EXPECT_EQ(revised[0].revision, 2u);
  EXPECT_EQ(All<SceneShown>(events)[0].title, "dinosaur title");
  const auto said = All<MessageSaid>(events);
  EXPECT_EQ(said[0].message_id, 2u);
  EXPECT_EQ(said[0].messages[0].text, "welcome to dinosaur");
  // The action's note, numbered with the revision it made.
  const auto lines = Lines(events);
  ASSERT_FALSE(lines.empty());
  EXPECT_NE(lines[0].find("(revision 2)"), std::string::npos) << lines[0];
  EXPECT_EQ(session.scene().name, "dinosaur");
}

TEST_F(ServerSessionTest, AHandMovingAControlIsForTheScreensOnly) {
  ServerSession session(Config(), worlds_["solar_system"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.controls.push_back(Event("lever", EventKind::kMoving, 1, 0.3));
  const Events events = session.Tick(in, now_, 1.0 / 60);
  EXPECT_EQ(Kinds(events), std::vector<std::string>{"ControlStateChanged"});
  const auto moving = All<ControlStateChanged>(events);
  EXPECT_FALSE(moving[0].settled);
  EXPECT_TRUE(moving[0].record.moving);
}

TEST_F(ServerSessionTest, ARefusedSampleOrAnotherParticipantsUseOfANameIsDroppedAndSaidOnce) {
  ServerSession session(Config(), worlds_["start_menu"]);
  StartAndWaitForModels(session);
  TickInputs in;
  in.members.push_back(Announced("alice", 1));
  ControlEventInput bad = Event("button_dino", EventKind::kPressed, -1, 1.0);
  bad.refused = "session is 'other'";
  in.controls.push_back(bad);
  // In alice's name from participant 2, while participant 1 announced her.
  in.controls.push_back(Event("button_dino", EventKind::kPressed, -1, 1.0, /*participant=*/2));
  const Events events = session.Tick(in, now_, 1.0 / 60);
  EXPECT_TRUE(All<ControlApplied>(events).empty());
  EXPECT_TRUE(All<SceneRevised>(events).empty());
  // The first bad sample of a sender on a topic is named; the next is counted.
  ASSERT_EQ(Lines(events).size(), 1u);
  EXPECT_NE(Lines(events)[0].find("session is 'other'"), std::string::npos) << Lines(events)[0];
  EXPECT_EQ(session.dropped().of("control_event"), 2u);
  EXPECT_EQ(session.scene().name, "start_menu");
}

TEST_F(ServerSessionTest, AContactSetGraspingAFreeBodyGivesOwnershipChangedAndTheBodyMovesAsItsOwners) {
  ServerSession session(Config(), scene::LoadScene(WriteBallScene(dir_.path())));
  StartAndWaitForModels(session);
  Clock::time_point now = now_;
  ContactSetInput c;
  c.set.session("s");
  c.set.user("alice");
  c.set.grasped_object_id("ball");
  c.set.simulating(true);
  c.set.simulated_object_id("ball");
  c.set.p_WO_m({0.0, 0.0, 0.1});
  c.set.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  c.writer = Key(1, 5);
  TickInputs in;
  in.contacts.push_back(c);
  now += std::chrono::milliseconds(10);
  const Events events = session.Tick(in, now, 0.01);
  const auto owned = All<OwnershipChanged>(events);
  ASSERT_EQ(owned.size(), 1u);
  EXPECT_EQ(owned[0].change.object_id, "ball");
  EXPECT_EQ(owned[0].change.previous_owner, "");
  EXPECT_EQ(owned[0].change.owner, "alice");
  EXPECT_EQ(owned[0].change.reason, OwnershipReason::kGranted);
  std::vector<BodyState> ball;
  for (const auto& m : All<BodyMoved>(events)) {
    if (m.body.object_id == "ball") ball.push_back(m.body);
  }
  ASSERT_EQ(ball.size(), 1u);
  EXPECT_EQ(ball[0].owner, "alice");
  EXPECT_NEAR(ball[0].X_WO.translation().z(), 0.1, 1e-12);  // at its owner's reported pose
}

// A killed server's log (what a session's events left in it) resumed: the restarted session
// starts through the same path, with the revision, message number, board and control places
// the log holds, and emits the same kinds of events a fresh start does (less the new world's
// reset), for the same consumers.
TEST_F(ServerSessionTest, AResumedStartReplaysTheLoggedStateThroughTheSamePath) {
  const auto file = dir_ / "log.sqlite";
  std::uint32_t revision = 0, message = 0;
  std::int64_t killed = 0;
  {
    SessionLog log(file, SessionStart{"s", 7, "h", 1, testing::kT0});
    SessionLogWriter writer(log);
    ServerSession session(Config(), worlds_["start_menu"]);
    writer.Take(session.Start(), now_);
    TickInputs in;
    in.controls.push_back(Event("book_solar", EventKind::kOpened, 0, 0.0));
    writer.Take(session.Tick(in, now_, 1.0 / 60), now_);
    in.controls[0] = Event("lever", EventKind::kMoved, 1, 0.5);
    const Events events = session.Tick(in, now_ + std::chrono::milliseconds(17), 1.0 / 60);
    writer.Take(events, now_ + std::chrono::milliseconds(17));
    revision = All<SceneRevised>(events).back().revision;
    message = All<MessageSaid>(events).back().message_id;
    log.Flush();
    killed = log.session_id();
  }
  ASSERT_EQ(revision, 3u);  // the book's world, then Mars' gravity
  ASSERT_EQ(message, 3u);
  // As a kill -9 leaves it: not ended.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(file.c_str(), &db), SQLITE_OK);
  sqlite3_exec(db, ("UPDATE sessions SET ended_unix_ns = NULL, last_seen_unix_ns = " + std::to_string(testing::kT0) +
                    " WHERE id = " + std::to_string(killed)).c_str(),
               nullptr, nullptr, nullptr);
  sqlite3_close(db);
  const auto resume = FindResumePoint(file, "s", testing::kT0 + testing::kSecond, 600 * testing::kSecond);
  ASSERT_TRUE(resume.has_value());

  ServerSession resumed(Config(), worlds_["start_menu"], &*resume);
  const Events events = resumed.Start();
  EXPECT_EQ(Kinds(events), (std::vector<std::string>{"SceneRevised", "SessionStateChanged", "RosterChanged", "LineSaid",
                                                     "SceneShown", "ControlStateChanged", "MessageSaid",
                                                     "SessionStateChanged"}));
  const auto revised = All<SceneRevised>(events);
  EXPECT_EQ(revised[0].scene.name, "solar_system");
  EXPECT_EQ(revised[0].scene.title, "Mars");
  EXPECT_EQ(revised[0].scene.gravity_W_m_per_s2.z(), -3.71);
  EXPECT_EQ(revised[0].revision, revision);  // the one the nodes have: they change nothing
  const auto lever = All<ControlStateChanged>(events);
  EXPECT_EQ(lever[0].record.control_id, "lever");
  EXPECT_EQ(lever[0].record.index, 1);
  EXPECT_EQ(lever[0].record.user, "alice");
  EXPECT_TRUE(lever[0].settled);
  const auto said = All<MessageSaid>(events);
  EXPECT_EQ(said[0].message_id, message);
  EXPECT_EQ(said[0].messages[0].text, "Now lift it on Mars.");
  EXPECT_EQ(All<SessionStateChanged>(events).back().state.message_id, message);
}

}  // namespace
}  // namespace handshare::server
