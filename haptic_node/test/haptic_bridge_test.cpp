// The haptic bridge's coupling path between its ticks, over real DDS (two participants of this
// process on loopback, a test domain of its own): a peer's contact set wakes the bridge through
// its reader's listener, is taken and handed to the haptic loop at once, and the loop's next
// step uses it, with no bridge tick in between (before, it waited for the next 100 Hz tick).
#include "haptic_bridge.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

#include "handshare/common/clock.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/haptic/sim_hand.hpp"
#include "desk_device.hpp"

namespace handshare::haptic {
namespace {

using namespace std::chrono_literals;
using Clock = HapticBridge::Clock;

constexpr int kDomain = 221;

// A scene "lab" (a soft block on the ground) in a fresh assets folder this process reads.
std::filesystem::path WriteLabAssets() {
  const auto dir = std::filesystem::temp_directory_path() / ("handshare_haptic_bridge_test_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  std::ofstream(dir / "scenes" / "lab.json") << R"({"name": "lab", "gravity_m_per_s2": [0, 0, -9.81], "objects": [
      {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
      {"id": "block", "kind": "deformable", "shape": "box", "position_m": [-0.1, 0, 0.01],
       "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.4}, "fixed": {"below_m": -0.0099}}],
      "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  return dir;
}

// Bob's index fingertip pressing the block's top 3 mm, in the block's frame O.
msg::ContactSet BobOnTheBlock(const std::string& session, std::uint64_t stamp_ns) {
  msg::ContactSet s;
  s.user("bob");
  s.session(session);
  s.stamp_ns(stamp_ns);
  auto& f = s.fingers()[1];
  f.active(true);
  f.object_id("block");
  f.p_OC_m({0.005, 0.0, 0.01});
  f.n_O({0.0, 0.0, 1.0});
  f.p_OE_m({0.005, 0.0, 0.015});
  f.radius_m(0.008);
  f.depth_m(0.003);
  f.u_O_m({0.0, 0.0, -0.003});
  f.f_O_N({0.0, 0.0, -0.5});
  return s;
}

// Alice's haptic node in a session of the test's domain, never rejoining.
HapticNodeConfig AliceIn(const std::string& session) {
  HapticNodeConfig config;
  config.where.domain_id = kDomain;
  config.where.session = session;
  config.user = "alice";
  config.rejoin_after_s = 0.0;
  return config;
}

// `server` plays the world server: it writes the lab's scene state once, and the bridge ticks
// every 10 ms until it has adopted it or give_up comes. The writer is returned to stay alive.
dds::Writer<msg::SceneState> ServeLab(dds::Participant& server, const std::string& session, HapticBridge& bridge,
                                      Clock::time_point give_up) {
  auto writer = dds::MakeWriter<msg::SceneState>(server, dds::topics::kSceneState);
  msg::SceneState scene;
  scene.session(session);
  scene.scene("lab");
  scene.revision(1);
  scene.gravity_W_m_per_s2({0.0, 0.0, -9.81});
  scene.tick_Hz(60.0f);
  writer.Write(scene);
  while (!bridge.heard_world_server() && Clock::now() < give_up) {
    bridge.Tick();
    std::this_thread::sleep_for(10ms);
  }
  return writer;
}

// Alice's node (a simulated hand far from the block: it touches nothing) and bob's participant,
// in one session of the test's domain.
struct AliceAndBob {
  explicit AliceAndBob(const std::string& session)
      : config(AliceIn(session)), alice_p(config.where, "haptic_node/alice"),
        bob_p(kDomain, session, "haptic_node/bob"), device(HandScript::Default(Eigen::Vector3d(0.2, 0.2, 0.3))),
        loop(device, HapticLoopConfig{1000.0, false}),
        bridge(config, device, loop, alice_p, nullptr, [](const std::string&) {}) {}
  HapticNodeConfig config;
  dds::Participant alice_p;
  dds::Participant bob_p;
  SimDevice device;
  HapticLoop loop;
  HapticBridge bridge;
};

class BridgeCoupling : public ::testing::Test {
 protected:
  void SetUp() override {
    assets_ = WriteLabAssets();
    setenv("HANDSHARE_ASSETS", assets_.c_str(), 1);
    setenv("HANDSHARE_CACHE", (assets_ / "cache").c_str(), 1);
  }
  void TearDown() override { std::filesystem::remove_all(assets_); }
  std::filesystem::path assets_;
};

// Bob's contact set, written while alice's bridge sleeps between its ticks, wakes it (the
// contact reader's listener posts its wake-up), is taken by the coupling stages alone and is
// used by alice's very next haptic step. With HapticNodeConfig::coupling_on_wake off (the
// bridge as it was: peers taken at its ticks only) the wait runs to its deadline and fails.
TEST_F(BridgeCoupling, APeersContactSetWakesTheBridgeAndReachesTheNextHapticStep) {
  const std::string session = "coupling_" + std::to_string(getpid());
  AliceAndBob ab(session);
  dds::Participant& bob_p = ab.bob_p;
  HapticLoop& loop = ab.loop;
  HapticBridge& bridge = ab.bridge;

  // Bob's side plays the world server too: the scene, then his contact set.
  auto contact_writer = dds::MakeWriter<msg::ContactSet>(bob_p, dds::topics::kContactSet);
  const auto give_up = Clock::now() + 60s;
  const auto scene_writer = ServeLab(bob_p, session, bridge, give_up);
  ASSERT_TRUE(bridge.heard_world_server()) << "no scene state in 60 s";
  while (contact_writer.matched_readers() == 0 && Clock::now() < give_up) std::this_thread::sleep_for(10ms);
  ASSERT_GT(contact_writer.matched_readers(), 0) << "alice's contact reader never matched bob's writer";
  double t_s = 0.0;
  loop.Step(t_s);  // the loop adopts the scene's renderer
  bridge.Tick();
  while (bridge.WaitForCoupling(Clock::now())) bridge.Couple();  // nothing owed before bob writes
  ASSERT_EQ(bridge.peer_contact_age().count(), 0u);

  const std::uint64_t stamp_ns = common::SteadyNowNs();
  contact_writer.Write(BobOnTheBlock(session, stamp_ns));
  // No tick from here on: only the wake-up can bring the set in.
  ASSERT_TRUE(bridge.WaitForCoupling(Clock::now() + 10s)) << "bob's contact set did not wake the bridge";
  bridge.Couple();
  EXPECT_EQ(bridge.peer_contact_age().count(), 1u) << "taken between ticks";
  loop.Step(t_s += 1e-3);  // alice's next haptic step
  bridge.Couple();         // reads that step's report: the step that first used bob's set
  ASSERT_EQ(bridge.peer_contact_loop_age().count(), 1u) << "the haptic step after the wake did not use bob's set";
  EXPECT_GT(bridge.peer_contact_loop_age().max_us(), 0.0);
}

// A bridge with nothing to carry (the hand far from the block, no peer, no viewer) asks for its
// next tick kIdleTick after the last instead of at its 10 ms period; a control's new state asks
// for a tick at once (its reader's listener); a peer's contact set, taken between ticks, makes
// the bridge busy again: its period comes back. Before, the bridge ticked every 10 ms whatever
// it had to do (docs/network.md, "CPU per node").
TEST_F(BridgeCoupling, ABridgeWithNothingToCarryAsksForIdleTicksUntilAPeersSetArrives) {
  const std::string session = "idle_" + std::to_string(getpid());
  AliceAndBob ab(session);
  const HapticNodeConfig& config = ab.config;
  dds::Participant& bob_p = ab.bob_p;
  HapticLoop& loop = ab.loop;
  HapticBridge& bridge = ab.bridge;
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / config.publish_Hz));
  EXPECT_EQ(bridge.TickPeriod(), period) << "no world yet: the bridge ticks at its period";

  auto contact_writer = dds::MakeWriter<msg::ContactSet>(bob_p, dds::topics::kContactSet);
  auto control_writer = dds::MakeWriter<msg::ControlState>(bob_p, dds::topics::kControlState);
  const auto give_up = Clock::now() + 60s;
  const auto scene_writer = ServeLab(bob_p, session, bridge, give_up);
  ASSERT_TRUE(bridge.heard_world_server()) << "no scene state in 60 s";
  while ((contact_writer.matched_readers() == 0 || control_writer.matched_readers() == 0) && Clock::now() < give_up) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(control_writer.matched_readers(), 0) << "alice's control reader never matched";
  double t_s = 0.0;
  loop.Step(t_s);
  bridge.Tick();
  while (bridge.WaitForCoupling(Clock::now())) bridge.Couple();
  EXPECT_EQ(bridge.TickPeriod(), Clock::duration(HapticBridge::kIdleTick)) << "nothing to carry: idle ticks";
  EXPECT_FALSE(bridge.TickAsked());

  msg::ControlState control;
  control.control_id("lever");
  control.session(session);
  control.scene("lab");
  control.changes(1);
  control.index(1);
  control_writer.Write(control);
  ASSERT_TRUE(bridge.WaitForCoupling(Clock::now() + 10s)) << "the control state did not wake the bridge";
  bridge.Couple();
  EXPECT_TRUE(bridge.TickAsked()) << "a control state is the tick's work: asked for at once";
  bridge.Tick();
  EXPECT_FALSE(bridge.TickAsked()) << "the tick took it";

  contact_writer.Write(BobOnTheBlock(session, common::SteadyNowNs()));
  ASSERT_TRUE(bridge.WaitForCoupling(Clock::now() + 10s)) << "bob's contact set did not wake the bridge";
  bridge.Couple();
  ASSERT_EQ(bridge.peer_contact_age().count(), 1u);
  EXPECT_EQ(bridge.TickPeriod(), period) << "a peer's contacts held: the bridge ticks at its period again";
}

// The person's input from their view (DeskInput), written while the bridge sleeps between its
// ticks, wakes it (the desk reader's listener) and reaches the desk device at once: the next
// haptic step's reading is live and heads for the target. Before, the input waited for the
// bridge's next 100 Hz tick (up to 10 ms of a desk's motion to photon); with coupling_on_wake
// off the wait runs to its deadline and fails.
TEST_F(BridgeCoupling, ADeskInputWakesTheBridgeAndReachesTheDevice) {
  const std::string session = "desk_" + std::to_string(getpid());
  const HapticNodeConfig config = AliceIn(session);
  dds::Participant alice_p(config.where, "haptic_node/alice");
  dds::Participant view_p(kDomain, session, "graphics_node/desk-alice");
  DeskDevice device;
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  HapticBridge bridge(config, device, loop, alice_p, nullptr, [](const std::string&) {});
  auto desk_writer = dds::MakeWriter<msg::DeskInput>(view_p, dds::topics::kDeskInput);
  const auto give_up = Clock::now() + 60s;
  while (desk_writer.matched_readers() == 0 && Clock::now() < give_up) std::this_thread::sleep_for(10ms);
  ASSERT_GT(desk_writer.matched_readers(), 0) << "alice's desk reader never matched the view's writer";
  bridge.Tick();
  while (bridge.WaitForCoupling(Clock::now())) bridge.Couple();  // nothing owed before the view writes
  ASSERT_EQ(bridge.desk_inputs(), 0u);

  msg::DeskInput input;
  input.user("alice");
  input.session(session);
  input.stamp_ns(common::SteadyNowNs());
  input.seq(1);
  input.p_WH_m({0.05, -0.2, 0.15});
  input.q_WH_wxyz({1.0, 0.0, 0.0, 0.0});
  input.focused(true);
  desk_writer.Write(input);
  // No tick from here on: only the wake-up can bring the input in.
  ASSERT_TRUE(bridge.WaitForCoupling(Clock::now() + 10s)) << "the desk input did not wake the bridge";
  bridge.Couple();
  EXPECT_EQ(bridge.desk_inputs(), 1u) << "taken between ticks";
  DeviceReading reading;
  device.Read(0.0, reading);
  EXPECT_TRUE(reading.valid) << "the desk's hand is not live after its first input";
}

// What a screen shows of a hand: a desk hand that moves sends its device state on the haptic
// step's motion wake-up (the step after it moved half a millimetre), with no tick, and while it
// moves the paced ticks send nothing more, so the rate stays the viewers' (here 100 Hz: a reader
// that did not say its frame rate). Without the motion wake-up no state leaves between ticks.
TEST_F(BridgeCoupling, AMovingHandsStateLeavesOnTheStepsWakeAtTheViewersRate) {
  const std::string session = "motion_" + std::to_string(getpid());
  const HapticNodeConfig config = AliceIn(session);
  dds::Participant alice_p(config.where, "haptic_node/alice");
  dds::Participant view_p(kDomain, session, "graphics_node/view-alice");
  DeskDevice device;
  HapticLoop loop(device, HapticLoopConfig{1000.0, false});
  HapticBridge bridge(config, device, loop, alice_p, nullptr, [](const std::string&) {});
  auto state_reader = dds::MakeReader<msg::DeviceState>(view_p, dds::topics::kDeviceState);
  const auto give_up = Clock::now() + 60s;
  const auto scene_writer = ServeLab(view_p, session, bridge, give_up);
  ASSERT_TRUE(bridge.heard_world_server()) << "no scene state in 60 s";
  while (state_reader.matched_writers() == 0 && Clock::now() < give_up) std::this_thread::sleep_for(10ms);
  ASSERT_GT(state_reader.matched_writers(), 0) << "the view's reader never matched alice's device states";

  // The hand at rest, high above the block.
  DeskTarget target;
  target.p_WH_m = {0.1, 0.1, 0.3};
  target.received_ns = common::SteadyNowNs();
  device.Post(target);
  double t_s = 0.0;
  for (int k = 0; k < 20; ++k) loop.Step(t_s += 1e-3);
  bridge.Tick();  // the motion wake-up is set with the rate
  while (bridge.WaitForCoupling(Clock::now())) bridge.Couple();
  for (int k = 0; k < 20; ++k) loop.Step(t_s += 1e-3);
  while (bridge.WaitForCoupling(Clock::now())) bridge.Couple();
  const std::uint64_t on_motion_before = bridge.device_states_on_motion();
  const std::uint64_t published_before = bridge.device_states_published();

  // 60 mm to the side (a quarter of a second at the desk's 0.25 m/s): the loop steps at 1 kHz,
  // the bridge takes only its wake-ups.
  target.p_WH_m = {0.16, 0.1, 0.3};
  target.received_ns = common::SteadyNowNs();
  device.Post(target);
  int first_at = -1;
  std::this_thread::sleep_for(20ms);  // longer than a period since the hand's last motion wake-up
  for (int k = 0; k < 40 && first_at < 0; ++k) {
    loop.Step(t_s += 1e-3);
    while (bridge.WaitForCoupling(Clock::now())) bridge.Couple();
    if (bridge.device_states_on_motion() > on_motion_before) first_at = k;
    std::this_thread::sleep_for(1ms);  // the loop's period, on the clock the wake-ups are spaced by
  }
  ASSERT_GE(first_at, 0) << "no device state left on a motion wake-up within 40 steps of the move";
  // The desk's filter moves the hand 0.5 mm in about 9 ms (12 m/s^2): the state leaves the step
  // after, not at a tick up to a period later.
  EXPECT_LE(first_at, 20);

  // Moving on for 150 ms of real time with the bridge's 100 Hz ticks as well: no more states
  // than the rate allows, and the moving hand's states are sent on its motion.
  const auto start = Clock::now();
  auto next_tick = start + 10ms;
  const std::uint64_t published_moving = bridge.device_states_published();
  while (Clock::now() - start < 150ms) {
    loop.Step(t_s += 1e-3);
    while (bridge.WaitForCoupling(Clock::now())) bridge.Couple();
    if (Clock::now() >= next_tick) {
      bridge.Tick();
      next_tick += 10ms;
    }
    std::this_thread::sleep_for(1ms);
  }
  const double elapsed_s = std::chrono::duration<double>(Clock::now() - start).count();
  const std::uint64_t sent = bridge.device_states_published() - published_moving;
  EXPECT_LE(static_cast<double>(sent), elapsed_s * 100.0 + 2.0) << "faster than the viewers' 100 Hz";
  EXPECT_GE(bridge.device_states_on_motion() - on_motion_before, sent / 2) << "the ticks, not the motion, sent them";
  EXPECT_GT(bridge.device_states_published(), published_before);
}

}  // namespace
}  // namespace handshare::haptic
