// bad_sample_publisher: a hostile or broken participant for tests. Joins a session and
// publishes malformed samples on every topic the nodes read (non-finite and huge numbers,
// wrong sizes, unknown kinds, another session's ids), round after round at --rate, until
// --duration passes; with --forge USER also well-formed samples in a present user's name; with
// --ghost MEMBER only a world server's roster that names a member nobody can hear. Each round's samples are described on stdout once, with their count at
// the end, so a test can compare what was sent with what the nodes dropped.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <thread>

#include "handshare/node/node_main.hpp"
#include "handshare/common/options.hpp"
#include "handshare/common/shutdown.hpp"
#include "handshare/dds/messages.hpp"

namespace {

using namespace handshare;
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

msg::ContactSet ContactSet(const std::string& session, const std::string& object) {
  msg::ContactSet s;
  s.session(session);
  s.user("mallory");
  auto& f = s.fingers()[1];
  f.active(true);
  f.object_id(object);
  f.p_OC_m({0.0, 0.0, 0.05});
  f.n_O({0.0, 0.0, 1.0});
  f.p_OE_m({0.0, 0.0, 0.05});
  f.radius_m(0.008);
  f.depth_m(0.002);
  f.u_O_m({0.0, 0.0, -0.002});
  f.f_O_N({0.0, 0.0, -1.0});
  s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  return s;
}

int Run(const common::Options& o) {
  const common::SessionOptions where = node::ReadSessionOptions(o);
  const std::string object = o.GetString("object");
  const double rate_Hz = o.GetDouble("rate", 1.0, 10000.0);
  dds::Participant participant(where, o.GetString("as"));
  if (const std::string ghost = o.GetString("ghost"); !ghost.empty()) {
    // A roster, as the world server writes it, naming a member no node hears: each node that
    // watches the roster should join again after its wait (RosterWatch).
    auto rosters = dds::MakeWriter<msg::SessionRoster>(participant, dds::topics::kSessionRoster);
    msg::SessionRoster roster;
    roster.session(where.session);
    roster.members().push_back(ghost);
    std::printf("bad_sample_publisher: a roster naming '%s', at %.0f Hz\n", ghost.c_str(), rate_Hz);
    std::fflush(stdout);
    const auto start = std::chrono::steady_clock::now();
    while (!common::ShutdownRequested() &&
           (where.duration.count() == 0 || std::chrono::steady_clock::now() - start < where.duration)) {
      rosters.Write(roster);
      std::this_thread::sleep_for(std::chrono::duration<double>(1.0 / rate_Hz));
    }
    return 0;
  }
  auto contacts = dds::MakeWriter<msg::ContactSet>(participant, dds::topics::kContactSet);
  auto objects = dds::MakeWriter<msg::ObjectState>(participant, dds::topics::kObjectState);
  auto events = dds::MakeWriter<msg::ControlEvent>(participant, dds::topics::kControlEvent);
  auto devices = dds::MakeWriter<msg::DeviceState>(participant, dds::topics::kDeviceState);
  auto deformations = dds::MakeWriter<msg::Deformation>(participant, dds::topics::kDeformation);
  auto scenes = dds::MakeWriter<msg::SceneState>(participant, dds::topics::kSceneState);
  auto boards = dds::MakeWriter<msg::MessageBoard>(participant, dds::topics::kMessageBoard);
  auto members = dds::MakeWriter<msg::MemberInfo>(participant, dds::topics::kMemberInfo);
  auto control_states = dds::MakeWriter<msg::ControlState>(participant, dds::topics::kControlState);

  // The round: one sample of each kind of damage.
  msg::ContactSet nan_u = ContactSet(where.session, object);
  nan_u.fingers()[1].u_O_m()[2] = kNan;
  msg::ContactSet huge_u = ContactSet(where.session, object);
  huge_u.fingers()[1].u_O_m()[2] = -5.0;  // a 5 m dent
  huge_u.user("mallory2");
  msg::ContactSet inf_f = ContactSet(where.session, object);
  inf_f.fingers()[1].f_O_N()[0] = kInf;
  inf_f.user("mallory3");
  msg::ContactSet foreign = ContactSet("another-session", object);  // forged: another session's
  foreign.user("mallory4");
  msg::ContactSet bad_body = ContactSet(where.session, object);
  bad_body.user("mallory5");
  bad_body.simulating(true);
  bad_body.simulated_object_id("ball");
  bad_body.grasped_object_id("ball");
  bad_body.p_WO_m({kNan, 0.0, 0.0});
  msg::ObjectState nan_pose;
  nan_pose.session(where.session);
  nan_pose.object_id("ball");
  nan_pose.p_WO_m({0.0, kNan, 0.0});
  nan_pose.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  msg::ObjectState zero_q = nan_pose;
  zero_q.p_WO_m({0.0, 0.0, 0.1});
  zero_q.q_WO_wxyz({0.0, 0.0, 0.0, 0.0});
  msg::ControlEvent bad_kind;
  bad_kind.session(where.session);
  bad_kind.user("mallory");
  bad_kind.control_id("lever");
  bad_kind.kind(static_cast<msg::ControlEventKind>(99));
  // With --forge USER: well-formed samples in a present user's name, from this participant (a
  // station claiming to be someone else): a press of the next-world arrow, a contact set and a hand.
  const std::string forge = o.GetString("forge");
  msg::ControlEvent forged_press;
  forged_press.session(where.session);
  forged_press.user(forge);
  forged_press.control_id("arrow_next");
  forged_press.kind(msg::CONTROL_PRESSED);
  forged_press.index(-1);
  msg::ContactSet forged_set = ContactSet(where.session, object);
  forged_set.user(forge);
  msg::DeviceState forged_hand;  // a plausible hand, 10 cm above the origin
  forged_hand.session(where.session);
  forged_hand.user(forge);
  forged_hand.q_WH_wxyz({1.0, 0.0, 0.0, 0.0});
  for (std::size_t i = 0; i < forged_hand.p_WE_m().size(); ++i) forged_hand.p_WE_m()[i] = {0.01 * i, 0.0, 0.1};
  msg::DeviceState inf_hand;
  inf_hand.session(where.session);
  inf_hand.user("mallory");
  inf_hand.q_WH_wxyz({1.0, 0.0, 0.0, 0.0});
  inf_hand.p_WE_m()[0][0] = kInf;
  msg::Deformation short_field;
  short_field.session(where.session);
  short_field.object_id(object);
  short_field.surface_node_count(10);
  short_field.node_ids({1, 2, 3});
  short_field.u_W_m({0.f, 0.f});  // 2 values for 3 ids
  // Written once per 100 rounds (reliable state: a few are enough to be seen).
  msg::SceneState smuggled;  // a scene name that reaches outside the scenes folder
  smuggled.session(where.session);
  smuggled.scene("../../../etc/passwd");
  smuggled.gravity_W_m_per_s2({0.0, 0.0, -9.81});
  msg::MessageBoard unlabelled;  // no language: no voice to speak it with
  unlabelled.session(where.session);
  unlabelled.message_id(99);
  unlabelled.text("mallory was here");
  msg::MemberInfo odd_member;  // a node kind that does not exist
  odd_member.member_id(where.session + "/mallory");
  odd_member.session(where.session);
  odd_member.user("mallory");
  odd_member.kind(static_cast<msg::NodeKind>(99));
  msg::ControlState wild_lever;  // a detent no control has
  wild_lever.control_id("lever_planet");
  wild_lever.session(where.session);
  wild_lever.scene("solar_system");
  wild_lever.index(5000);
  std::printf("bad_sample_publisher: per round 5 contact_set (nan u, 5 m u, inf f, another session, nan body "
              "pose), 2 object_state (nan position, zero quaternion), 1 control_event (kind 99), 1 device_state "
              "(inf fingertip), 1 deformation (2 values for 3 ids), at %.0f Hz; every 100 rounds 1 scene_state "
              "(scene '../../../etc/passwd'), 1 message_board (no language), 1 member_info (kind 99), 1 control_state "
              "(index 5000)\n",
              rate_Hz);
  if (!forge.empty()) {
    std::printf("bad_sample_publisher: and in user '%s''s name: 1 contact_set, 1 device_state, 1 control_event "
                "(arrow_next pressed)\n",
                forge.c_str());
  }
  std::fflush(stdout);

  const auto period = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(1.0 / rate_Hz));
  const auto start = std::chrono::steady_clock::now();
  auto next = start;
  std::uint64_t rounds = 0;
  while (!common::ShutdownRequested() &&
         (where.duration.count() == 0 || std::chrono::steady_clock::now() - start < where.duration)) {
    for (const auto* s : {&nan_u, &huge_u, &inf_f, &foreign, &bad_body}) contacts.Write(*s);
    objects.Write(nan_pose);
    objects.Write(zero_q);
    // Reliable keep-all: one bad event per 100 rounds is enough to be seen, not a queue flood.
    if (rounds % 100 == 0) {
      events.Write(bad_kind);
      scenes.Write(smuggled);
      boards.Write(unlabelled);
      members.Write(odd_member);
      control_states.Write(wild_lever);
    }
    if (!forge.empty()) {
      contacts.Write(forged_set);
      devices.Write(forged_hand);
      if (rounds % 100 == 0) events.Write(forged_press);
    }
    devices.Write(inf_hand);
    deformations.Write(short_field);
    ++rounds;
    next += period;
    std::this_thread::sleep_until(next);
  }
  std::printf("bad_sample_publisher: %llu rounds sent\n", static_cast<unsigned long long>(rounds));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  handshare::common::Options options("bad_sample_publisher",
                                     "Publishes malformed samples on every topic of a session (a test's hostile peer).");
  handshare::node::DeclareSessionOptions(options);
  options.Value("object", "ID", "the object the bad contact sets and deformations name", "tail")
      .Value("rate", "HZ", "rounds per second", "1000")
      .Value("forge", "USER", "also write well-formed samples in this user's name (\"\": none)", "")
      .Value("ghost", "MEMBER", "write nothing but a world server's roster naming this member id (\"\": none)", "")
      .Value("as", "NAME", "participant name; with --security it picks the identity (e.g. graphics_node/x: a "
                           "spectator's)", "bad_sample_publisher");
  return handshare::node::RunNodeMain(argc, argv, options, [](const handshare::common::Options& o) { return Run(o); });
}
