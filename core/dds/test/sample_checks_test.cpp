// Received samples are checked before they touch a simulation: every kind of bad value is
// named, and good samples pass.
#include "handshare/dds/sample_checks.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include <limits>
#include <string>
#include <vector>

namespace handshare::dds {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

msg::ContactSet GoodContacts() {
  msg::ContactSet s;
  s.session("museum");
  s.user("bob");
  auto& f = s.fingers()[1];
  f.active(true);
  f.object_id("tail");
  f.p_OC_m({0.1, 0.0, 0.05});
  f.n_O({0.0, 0.0, 1.0});
  f.p_OE_m({0.1, 0.0, 0.052});
  f.radius_m(0.008);
  f.depth_m(0.002);
  f.u_O_m({0.0, 0.0, -0.002});
  f.f_O_N({0.0, 0.0, -1.0});
  s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  return s;
}

TEST(SampleChecks, AGoodContactSetPasses) { EXPECT_EQ(CheckContactSet(GoodContacts(), "museum"), ""); }

TEST(SampleChecks, ContactSetsWithBadNumbersAreNamed) {
  auto s = GoodContacts();
  s.fingers()[1].u_O_m()[1] = kNan;
  EXPECT_EQ(CheckContactSet(s, "museum"), "fingers[1].u_O_m[1] is nan");
  s = GoodContacts();
  s.fingers()[1].f_O_N()[0] = -kInf;
  EXPECT_EQ(CheckContactSet(s, "museum"), "fingers[1].f_O_N[0] is -inf");
  s = GoodContacts();
  s.fingers()[1].u_O_m()[2] = -5.0;  // a 5 m dent: pushes a user's finger with no bound
  EXPECT_NE(CheckContactSet(s, "museum").find("fingers[1].u_O_m has norm 5"), std::string::npos);
  s = GoodContacts();
  s.fingers()[1].radius_m(-0.01);
  EXPECT_NE(CheckContactSet(s, "museum").find("fingers[1].radius_m is -0.01"), std::string::npos);
  s = GoodContacts();
  s.fingers()[1].object_id("");
  EXPECT_EQ(CheckContactSet(s, "museum"), "fingers[1].object_id is empty");
  // An inactive finger's garbage is never read, so it is not checked.
  s = GoodContacts();
  s.fingers()[3].u_O_m()[0] = kNan;
  EXPECT_EQ(CheckContactSet(s, "museum"), "");
}

TEST(SampleChecks, AnotherSessionsOrAnonymousSampleIsRefused) {
  auto s = GoodContacts();
  EXPECT_EQ(CheckContactSet(s, "lab"), "session 'museum' is not this session ('lab')");
  s.user("");
  EXPECT_EQ(CheckContactSet(s, "museum"), "user is empty");
}

TEST(SampleChecks, ASimulatedBodyNeedsAFinitePoseAUnitQuaternionAndAPlausibleSpeed) {
  auto s = GoodContacts();
  s.simulating(true);
  s.simulated_object_id("ball");
  EXPECT_EQ(CheckContactSet(s, "museum"), "");
  s.q_WO_wxyz({0.0, 0.0, 0.0, 0.0});
  EXPECT_NE(CheckContactSet(s, "museum").find("q_WO_wxyz has norm 0"), std::string::npos);
  s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  s.v_WO_m_per_s({1e6, 0.0, 0.0});
  EXPECT_NE(CheckContactSet(s, "museum").find("v_WO_m_per_s has norm"), std::string::npos);
}

TEST(SampleChecks, ObjectStates) {
  msg::ObjectState s;
  s.session("museum");
  s.object_id("ball");
  s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  EXPECT_EQ(CheckObjectState(s, "museum"), "");
  s.p_WO_m()[2] = kNan;
  EXPECT_EQ(CheckObjectState(s, "museum"), "p_WO_m[2] is nan");
  s.p_WO_m()[2] = 1e9;
  EXPECT_NE(CheckObjectState(s, "museum").find("p_WO_m has norm"), std::string::npos);
}

TEST(SampleChecks, SceneStatesNameAPlainWorldWithFiniteGravity) {
  msg::SceneState s;
  s.session("museum");
  s.scene("dinosaur");
  s.gravity_W_m_per_s2({0.0, 0.0, -9.81});
  EXPECT_EQ(CheckSceneState(s, "museum"), "");
  s.scene("../../etc/passwd");
  EXPECT_NE(CheckSceneState(s, "museum").find("is not a plain name"), std::string::npos);
  s.scene("dinosaur");
  s.gravity_W_m_per_s2({0.0, 0.0, kNan});
  EXPECT_EQ(CheckSceneState(s, "museum"), "gravity_W_m_per_s2[2] is nan");
  s.gravity_W_m_per_s2({0.0, 0.0, -9.81});
  s.tick_Hz(std::numeric_limits<float>::infinity());
  EXPECT_EQ(CheckSceneState(s, "museum"), "tick_Hz is inf (expected 0 to 10000)");
}

// A visitor's questionnaire: every score 0 (not answered) or 1..7, one answered at least, the
// sender and the visitor named, this session's.
TEST(SampleChecks, VisitAnswersOutsideTheScaleOrEmptyAreRefused) {
  msg::VisitAnswers v;
  v.session("museum");
  v.user("web-console");
  v.visitor("alice");
  v.scores()[3][2] = 7;
  EXPECT_EQ(CheckVisitAnswers(v, "museum"), "");
  EXPECT_NE(CheckVisitAnswers(v, "other").find("session"), std::string::npos);
  v.scores()[1][0] = 8;
  EXPECT_EQ(CheckVisitAnswers(v, "museum"), "scores[1][0] 8 is not 0..7");
  v.scores()[1][0] = 255;
  EXPECT_EQ(CheckVisitAnswers(v, "museum"), "scores[1][0] 255 is not 0..7");
  v.scores()[1][0] = 0;
  v.scores()[3][2] = 0;
  EXPECT_EQ(CheckVisitAnswers(v, "museum"), "no score answered");
  v.scores()[0][0] = 1;
  v.visitor("");
  EXPECT_NE(CheckVisitAnswers(v, "museum").find("visitor"), std::string::npos);
  v.visitor("alice");
  v.user("");
  EXPECT_NE(CheckVisitAnswers(v, "museum").find("user"), std::string::npos);
}

// An operator's command: this session's, the sender named, a kind the IDL has, the world of
// GO_TO_WORLD a world's name, the visitor of END_TURN named.
TEST(SampleChecks, OperatorCommandsOfUnknownKindOrWithoutTheirNameAreRefused) {
  msg::OperatorCommand c;
  c.session("museum");
  c.user("web-console");
  c.kind(msg::OPERATOR_GO_TO_WORLD);
  c.world("dinosaur");
  EXPECT_EQ(CheckOperatorCommand(c, "museum"), "");
  EXPECT_NE(CheckOperatorCommand(c, "other").find("session"), std::string::npos);
  c.world("../dinosaur");
  EXPECT_EQ(CheckOperatorCommand(c, "museum"), "world '../dinosaur' is not a world's name ([a-z0-9_])");
  c.world("");
  EXPECT_NE(CheckOperatorCommand(c, "museum").find("world"), std::string::npos);
  c.kind(msg::OPERATOR_RESTART_TOUR);
  EXPECT_EQ(CheckOperatorCommand(c, "museum"), "");
  c.kind(msg::OPERATOR_END_TURN);
  EXPECT_NE(CheckOperatorCommand(c, "museum").find("visitor"), std::string::npos);
  c.visitor("alice");
  EXPECT_EQ(CheckOperatorCommand(c, "museum"), "");
  c.kind(static_cast<msg::OperatorCommandKind>(7));
  EXPECT_EQ(CheckOperatorCommand(c, "museum"), "kind 7 is not an operator command");
  c.kind(msg::OPERATOR_RESTART_TOUR);
  c.user("");
  EXPECT_NE(CheckOperatorCommand(c, "museum").find("user"), std::string::npos);
}

TEST(SampleChecks, ControlEventsOfUnknownKindOrIndexAreRefused) {
  msg::ControlEvent e;
  e.session("museum");
  e.user("alice");
  e.control_id("lever");
  e.kind(msg::CONTROL_MOVED);
  e.index(1);
  EXPECT_EQ(CheckControlEvent(e, "museum"), "");
  e.kind(static_cast<msg::ControlEventKind>(99));
  EXPECT_EQ(CheckControlEvent(e, "museum"), "kind 99 is not a control event kind");
  e.kind(msg::CONTROL_MOVED);
  e.index(-7);
  EXPECT_NE(CheckControlEvent(e, "museum").find("index is -7"), std::string::npos);
  // Motion: where the control is (finite, radians or metres) and whether it still moves (1, 0).
  e.kind(msg::CONTROL_MOVING);
  e.index(1);
  e.value(0.3);
  EXPECT_EQ(CheckControlEvent(e, "museum"), "");
  e.value(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(CheckControlEvent(e, "museum"), "value is nan (expected -10 to 10)");
  e.value(0.3);
  e.index(2);
  EXPECT_EQ(CheckControlEvent(e, "museum"), "index is 2 (expected 0 to 1)");
}

TEST(SampleChecks, DeformationsNeedThreeDisplacementsPerIdAndIdsInRange) {
  msg::Deformation d;
  d.session("museum");
  d.object_id("tail");
  d.surface_node_count(10);
  d.node_ids({1, 9});
  d.u_W_m({0.f, 0.f, -1e-3f, 0.f, 0.f, 0.f});
  EXPECT_EQ(CheckDeformation(d, "museum"), "");
  d.node_ids({1, 10});
  EXPECT_EQ(CheckDeformation(d, "museum"), "node_ids[1] = 10 is not below surface_node_count 10");
  d.node_ids({1});
  EXPECT_EQ(CheckDeformation(d, "museum"), "6 displacements for 1 node ids (3 each)");
  d.node_ids({1, 2});
  d.u_W_m()[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(CheckDeformation(d, "museum"), "u_W_m of node_ids[1][1] is nan");
}

TEST(SampleChecks, DeviceStatesBoardsAndMembers) {
  msg::DeviceState d;
  d.session("museum");
  d.user("alice");
  d.q_WH_wxyz({1.0, 0.0, 0.0, 0.0});
  d.fingertip_radius_m(0.008);
  EXPECT_EQ(CheckDeviceState(d, "museum"), "");
  d.p_WE_m()[4][0] = kInf;
  EXPECT_EQ(CheckDeviceState(d, "museum"), "p_WE_m[4][0] is inf");
  d.p_WE_m()[4][0] = 0.0;
  d.q_hand_rad()[7] = std::nan("");
  EXPECT_EQ(CheckDeviceState(d, "museum"), "q_hand_rad[7] is nan (expected -20 to 20)");
  d.q_hand_rad()[7] = 0.3;
  d.q_arm_rad()[2] = 1e6;
  EXPECT_EQ(CheckDeviceState(d, "museum"), "q_arm_rad[2] is 1e+06 (expected -20 to 20)");
  d.q_arm_rad()[2] = 0.0;
  EXPECT_EQ(CheckDeviceState(d, "museum"), "");
  msg::MessageBoard b;
  b.session("museum");
  b.language("en");
  EXPECT_EQ(CheckMessageBoard(b, "museum"), "");
  b.session("lab");
  EXPECT_NE(CheckMessageBoard(b, "museum"), "");
  b.session("museum");
  b.language("fr");
  EXPECT_EQ(CheckMessageBoard(b, "museum"), "language 'fr' is not en or ja");
  // A Japanese board carries the kana the audio guide speaks; a kanji in it would go unspoken.
  b.language("ja");
  EXPECT_EQ(CheckMessageBoard(b, "museum"), "reading is empty");
  b.reading("つきです");
  EXPECT_EQ(CheckMessageBoard(b, "museum"), "");
  b.reading("月です");
  EXPECT_EQ(CheckMessageBoard(b, "museum"), "reading: byte 0 is not kana, ASCII, 、 or 。");
  msg::MemberInfo m;
  m.session("museum");
  m.user("alice");
  m.kind(msg::NODE_HAPTIC);
  EXPECT_EQ(CheckMemberInfo(m, "museum"), "");
  m.kind(static_cast<msg::NodeKind>(12));
  EXPECT_EQ(CheckMemberInfo(m, "museum"), "kind 12 is not a node kind");
  m.kind(msg::NODE_GRAPHICS);
  m.view_Hz(30.0f);
  EXPECT_EQ(CheckMemberInfo(m, "museum"), "");
  m.view_Hz(-1.0f);
  EXPECT_EQ(CheckMemberInfo(m, "museum"), "view_Hz is -1 (expected 0 to 10000)");
}

// Loop statistics go to the operator's page and the session log: every number is named.
TEST(SampleChecks, LoopStatisticsNameTheirBadNumber) {
  msg::LoopStatistics s;
  s.session("museum");
  s.node("haptic_node/alice");
  s.rate_Hz(1000.0);
  s.sent_bytes_per_s(2.5e4);
  EXPECT_EQ(CheckLoopStatistics(s, "museum"), "");
  EXPECT_EQ(CheckLoopStatistics(s, "other"), "session 'museum' is not this session ('other')");
  s.sent_bytes_per_s(-1.0);
  EXPECT_EQ(CheckLoopStatistics(s, "museum"), "sent_bytes_per_s is -1 (expected 0 to 1e+09)");
  s.sent_bytes_per_s(0.0);
  s.jitter_p99_us(std::nan(""));
  EXPECT_EQ(CheckLoopStatistics(s, "museum"), "jitter_p99_us is nan (expected 0 to 1e+09)");
  s.jitter_p99_us(1.0);
  s.node("");
  EXPECT_EQ(CheckLoopStatistics(s, "museum"), "node is empty");
}

// A device's fingers and capabilities (docs/devices.md): at least one finger, no sixth; as many
// fingers as contact points.
TEST(SampleChecks, ADeviceHasOneToFiveFingersAndSaysWhichItHas) {
  msg::DeviceState d;
  d.session("museum");
  d.user("carol");
  d.q_WH_wxyz({1.0, 0.0, 0.0, 0.0});
  d.fingertip_radius_m(0.008);
  d.absent_fingers(0b11101);  // a stylus: the index finger only
  EXPECT_EQ(CheckDeviceState(d, "museum"), "");
  d.absent_fingers(0b11111);
  EXPECT_EQ(CheckDeviceState(d, "museum"), "absent_fingers 31: a device without a finger");
  d.absent_fingers(0b100000);
  EXPECT_EQ(CheckDeviceState(d, "museum"), "absent_fingers 32 names a sixth finger");
  msg::MemberInfo m;
  m.session("museum");
  m.user("carol");
  m.kind(msg::NODE_HAPTIC);
  msg::DeviceCaps caps;
  caps.contact_points(2);
  caps.finger_mask(0b00011);
  caps.max_force_N(12.0f);
  caps.workspace_radius_m(0.08f);
  caps.rate_Hz(1000.0f);
  m.device_caps(caps);
  EXPECT_EQ(CheckMemberInfo(m, "museum"), "");
  caps.finger_mask(0b00001);
  m.device_caps(caps);
  EXPECT_EQ(CheckMemberInfo(m, "museum"), "device_caps: 2 contact points on finger mask 1 (1 to 5 points, one per finger 0 to 4)");
  caps.finger_mask(0b00011);
  caps.rate_Hz(std::nanf(""));
  m.device_caps(caps);
  EXPECT_EQ(CheckMemberInfo(m, "museum"), "device_caps.rate_Hz is nan (expected 0 to 100000)");
}

TEST(SampleChecks, ControlStatesNameAControlOfAWorldAndAPlausibleIndex) {
  msg::ControlState s;
  s.session("museum");
  s.control_id("lever_planet");
  s.scene("solar_system");
  s.index(1);
  EXPECT_EQ(CheckControlState(s, "museum"), "");
  EXPECT_NE(CheckControlState(s, "lab"), "");
  s.index(-7);
  EXPECT_EQ(CheckControlState(s, "museum"), "index is -7 (expected -1 to 1000)");
  s.index(0);
  s.position(std::numeric_limits<double>::infinity());
  EXPECT_EQ(CheckControlState(s, "museum"), "position is inf (expected -10 to 10)");
  s.position(0.2);
  s.control_id("");
  EXPECT_EQ(CheckControlState(s, "museum"), "control_id is empty");
}

TEST(SampleChecks, ARosterIsTheSessionsAndNamesEveryMember) {
  msg::SessionRoster s;
  s.session("museum");
  EXPECT_EQ(CheckSessionRoster(s, "museum"), "");  // nobody yet
  s.members().push_back("museum/alice");
  s.members().push_back("museum/spectator-1");
  EXPECT_EQ(CheckSessionRoster(s, "museum"), "");
  EXPECT_NE(CheckSessionRoster(s, "lab"), "");
  s.members().push_back("");
  EXPECT_EQ(CheckSessionRoster(s, "museum"), "members[2] is empty");
}

TEST(DroppedSamples, CountsPerTopicAndPrintsAFloodOncePerThousand) {
  DroppedSamples d;
  EXPECT_EQ(d.Summary(), "none");
  std::size_t lines = 0;
  for (int i = 0; i < 2500; ++i) lines += d.Count("contact_set", "mallory", "x is nan").empty() ? 0 : 1;
  EXPECT_EQ(lines, 3u);  // the 1st, 1000th and 2000th
  // Another sender is named at its first bad sample.
  EXPECT_FALSE(d.Count("contact_set", "trudy", "y is inf").empty());
  // Forged names, one per sample: only the first 64 senders are named, then one per 1000.
  lines = 0;
  for (int i = 0; i < 999; ++i) lines += d.Count("contact_set", "forged" + std::to_string(i), "z").empty() ? 0 : 1;
  EXPECT_LE(lines, 64u);
  EXPECT_NE(d.Count("object_state", "mallory", "p is nan").find("dropped a bad object_state sample from 'mallory'"),
            std::string::npos);
  EXPECT_EQ(d.of("contact_set"), 3500u);
  EXPECT_EQ(d.total(), 3501u);
  EXPECT_EQ(d.Summary(), "contact_set 3500, object_state 1");
  // Accept: a good sample passes uncounted; a bad one is counted and its line said once.
  std::vector<std::string> said;
  const auto say = [&](const std::string& line) { said.push_back(line); };
  EXPECT_TRUE(d.Accept("device_state", "alice", "", say));
  EXPECT_FALSE(d.Accept("device_state", "alice", "p is nan", say));
  EXPECT_FALSE(d.Accept("device_state", "alice", "p is nan", say));
  EXPECT_EQ(d.of("device_state"), 2u);
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said[0].find("dropped a bad device_state sample from 'alice': p is nan"), std::string::npos);
}

// A desk's input drives a hand: a target far away, a rotation that is none or a closure
// beyond closed is refused, named, never smoothed into the loop.
TEST(SampleChecks, DeskInputs) {
  msg::DeskInput d;
  d.session("museum");
  d.user("alice");
  d.p_WH_m({0.0, -0.2, 0.15});
  d.q_WH_wxyz({1.0, 0.0, 0.0, 0.0});
  d.closure({0.0, 0.5, 1.0, 0.0, 0.0});
  EXPECT_EQ(CheckDeskInput(d, "museum"), "");
  EXPECT_NE(CheckDeskInput(d, "lab"), "");
  d.closure()[2] = 1.5;
  EXPECT_EQ(CheckDeskInput(d, "museum"), "closure[2] is 1.5 (expected 0 to 1)");
  d.closure()[2] = 1.0;
  d.q_WH_wxyz({0.0, 0.0, 0.0, 0.0});
  EXPECT_EQ(CheckDeskInput(d, "museum"), "q_WH_wxyz has norm 0 (a rotation's is 1)");
  d.q_WH_wxyz({1.0, 0.0, 0.0, 0.0});
  d.p_WH_m()[1] = std::nan("");
  EXPECT_EQ(CheckDeskInput(d, "museum"), "p_WH_m[1] is nan");
  d.p_WH_m()[1] = 0.0;
  d.user("");
  EXPECT_NE(CheckDeskInput(d, "museum"), "");
}

}  // namespace
}  // namespace handshare::dds
