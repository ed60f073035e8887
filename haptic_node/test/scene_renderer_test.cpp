// SceneRenderer following a body simulated elsewhere: between the (display-rate) samples the
// body moves on at its published velocity from where it was when the sample arrived (dead
// reckoning, capped), instead of standing still and jumping by v / 60 Hz at the next sample.
#include "handshare/haptic/scene_renderer.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <nlohmann/json.hpp>

#include "bridge_conversions.hpp"
#include "local_field_dump.hpp"
#include "handshare/common/clock.hpp"
#include "handshare/common/wakeup.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/session/contact_deadband.hpp"
#include "handshare/session/peer_contacts.hpp"
#include "handshare/testing/allocation_counter.hpp"

namespace handshare::haptic {
namespace {

TEST(SceneRenderer, FollowedBodyGlidesOnAtItsPublishedVelocityBetweenSamples) {
  const auto dir = std::filesystem::temp_directory_path() / "handshare_scene_renderer_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  const auto file = dir / "scenes" / "moon.json";
  std::ofstream(file) << R"({"name": "moon", "gravity_m_per_s2": [0, 0, -1.62], "objects": [
      {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
      {"id": "ball", "kind": "rigid", "shape": "sphere", "position_m": [0, 0, 0.04], "radius_m": 0.04, "mass_kg": 0.2}],
      "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  world::SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneRenderer r(scene::LoadScene(file), options);
  const auto ball = r.models().Find("ball");
  ASSERT_GE(ball, 0);
  DeviceReading far;
  for (auto& p : far.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  far.valid = true;
  std::array<Eigen::Vector3d, kFingers> f{};

  auto follow = [&](double age_s) -> Eigen::Vector3d {
    FollowedBodies fb;
    fb.count = 1;
    fb.items[0].object = ball;
    fb.items[0].p_WO_m[0] = 0.0;
    fb.items[0].p_WO_m[1] = 0.0;
    fb.items[0].p_WO_m[2] = 0.2;
    fb.items[0].v_WO_m_per_s[0] = 0.5;
    fb.items[0].received_ns = common::SteadyNowNs() - static_cast<std::uint64_t>(age_s * 1e9);
    r.SetFollowed(fb);
    r.Render(0.0, 1e-3, common::SteadyNowNs(), far, f);
    return r.models().world->pose(ball).translation();
  };
  // A sample that arrived 20 ms ago: 10 mm on (+ the step's own 0.5 mm), not where it was.
  const Eigen::Vector3d p20 = follow(0.020);
  EXPECT_GT(p20.x(), 0.5 * 0.020 + 0.5e-3 - 1e-6);
  EXPECT_LT(p20.x(), 0.5 * 0.025 + 0.5e-3);  // 5 ms for the test's own scheduling
  EXPECT_NEAR(r.models().world->body_velocity_W(ball).x(), 0.5, 1e-3);  // less 1 ms of air damping
  // A sample that stopped coming 10 s ago (a lost server): at most 0.1 s of dead reckoning.
  const Eigen::Vector3d p10 = follow(10.0);
  EXPECT_NEAR(p10.x(), 0.5 * FollowedBodies::kMaxDeadReckoning_s + 0.5e-3, 1e-6);
  std::filesystem::remove_all(dir);
}

// The newest peer set's sender stamp comes back in the report with the step that first used
// it (the bridge turns the two into the set's age at the haptic loop, bench/net); a set the
// loop already used keeps its first step's time. Every report carries its step's time.
TEST(SceneRenderer, ReportsTheStepThatFirstUsedANewPeerSet) {
  const auto dir = std::filesystem::temp_directory_path() / "handshare_scene_renderer_peer_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  const auto file = dir / "scenes" / "flat.json";
  std::ofstream(file) << R"({"name": "flat", "gravity_m_per_s2": [0, 0, -9.81], "objects": [
      {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]}],
      "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  world::SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneRenderer r(scene::LoadScene(file), options);
  DeviceReading far;
  for (auto& p : far.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  far.valid = true;
  std::array<Eigen::Vector3d, kFingers> f{};
  ContactReport report;

  r.Render(0.0, 1e-3, common::SteadyNowNs(), far, f);
  ASSERT_TRUE(r.TakeReport(report));
  EXPECT_EQ(report.peer_stamp_ns, 0u);  // no peer set yet
  EXPECT_EQ(report.peer_seen_ns, 0u);

  RemoteContacts remote;
  remote.newest_stamp_ns = common::SteadyNowNs();
  r.SetRemote(remote);
  const std::uint64_t before = common::SteadyNowNs();
  r.Render(0.0, 1e-3, common::SteadyNowNs(), far, f);
  const std::uint64_t after = common::SteadyNowNs();
  ASSERT_TRUE(r.TakeReport(report));
  EXPECT_EQ(report.peer_stamp_ns, remote.newest_stamp_ns);
  EXPECT_GE(report.peer_seen_ns, before);
  EXPECT_LE(report.peer_seen_ns, after);
  EXPECT_GE(report.step_ns, before);  // the step's own time: the sender's report age
  EXPECT_LE(report.step_ns, after);

  // The same set again (the bridge sends the newest every tick): the first step's time stays.
  const std::uint64_t first_seen = report.peer_seen_ns;
  r.SetRemote(remote);
  r.Render(0.0, 1e-3, common::SteadyNowNs(), far, f);
  ASSERT_TRUE(r.TakeReport(report));
  EXPECT_EQ(report.peer_seen_ns, first_seen);
  std::filesystem::remove_all(dir);
}

// A fresh folder for a test's scene and caches.
std::filesystem::path LabDir(const std::string& what) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("handshare_scene_renderer_" + what + "_test_" + std::to_string(getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir / "scenes");
  return dir;
}
// A scene "lab" with these objects (JSON, without the brackets), written under dir/scenes.
std::filesystem::path WriteLab(const std::filesystem::path& dir, const std::string& objects) {
  const auto file = dir / "scenes" / "lab.json";
  std::ofstream(file) << R"({"name": "lab", "gravity_m_per_s2": [0, 0, -9.81], "objects": [)" << objects
                      << R"(], "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  return file;
}

// The fade tests' lab: a soft block on the ground.
constexpr const char* kGroundAndBlock = R"(
      {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
      {"id": "block", "kind": "deformable", "shape": "box", "position_m": [-0.1, 0, 0.01],
       "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.4}, "fixed": {"below_m": -0.0099}})";

// Bob's fingertip on the block's top, 5 mm from alice's, 3 mm deep (u and f scaled by weight),
// in the block's frame O (at (-0.1, 0, 0.01) in W): (-0.095, 0, 0.02) in W.
msg::ContactSet BobOnTheBlock(double weight) {
  msg::ContactSet s;
  s.user("bob");
  s.session("s");
  s.fingers()[0].active(true);
  s.fingers()[0].object_id("block");
  s.fingers()[0].p_OC_m({0.005, 0.0, 0.01});
  s.fingers()[0].u_O_m({0.0, 0.0, weight * -0.003});
  s.fingers()[0].f_O_N({0.0, 0.0, weight * -0.5});
  return s;
}

// A peer that vanished fades out at the haptic rate whatever the bridge does. The bridge
// (ReceivePeers, ~100 Hz) hands the peers' contacts over; under load it stalls for tens to
// 100+ ms. Here bob's last set arrives at t0, the bridge ticks every 10 ms but stalls from
// 250 to 400 ms (inside the fade, 200-500 ms), and the haptic thread steps every 1 ms while
// alice presses the same block. Oracle: a second renderer, stepped with the same readings,
// is handed at every step a fresh copy of bob's set with u and f scaled by the fade law's
// weight at that step's time, i.e. a weight that moves by exactly (fade rate x 1 ms) per step.
// Alice's force must be the oracle's at every step, so it never moves faster than the fade.
// With the weight computed by the bridge, the stall held it at 0.87 and the next tick stepped
// it to 0.33 in one haptic step (net.partitioned_user, load 10: 0.0355 N in one 7 ms row).
TEST(SceneRenderer, AVanishedPeerFadesAtTheHapticRateWhileTheBridgeStalls) {
  using namespace std::chrono_literals;
  using Clock = session::PeerContacts::Clock;
  const auto dir = LabDir("fade");
  const auto file = WriteLab(dir, kGroundAndBlock);
  world::SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  const scene::Scene scene = scene::LoadScene(file);
  SceneRenderer r(scene, options);
  SceneRenderer oracle(scene, options);
  // The fade law alone: the coupling's passivity controller (its own tests: contact's
  // CouplingPassivity.*, CouplingStability.*) would take bob's 3 mm jump at its rate limit and
  // within the energy his set carries, and the oracle, handed a new set every step, differently.
  r.SetCouplingPassivity(false);
  oracle.SetCouplingPassivity(false);
  ASSERT_GE(r.models().Find("block"), 0);

  const auto t0 = Clock::now();
  std::array<Eigen::Vector3d, kFingers> f{};
  // One haptic step of `renderer` at t0 + t_ms; alice's index finger's force along z [N].
  auto step = [&](SceneRenderer& renderer, const DeviceReading& reading, double t_ms) {
    const auto step_ns = session::PeerContacts::SteadyNs(t0) + static_cast<std::uint64_t>(t_ms * 1e6);
    renderer.Render(0.0, 1e-3, step_ns, reading, f);
    return f[0].z();
  };

  // Alice's index finger comes down onto the block's top (z = 0.02 m) and presses 2 mm.
  DeviceReading alice;
  alice.valid = true;
  for (auto& p : alice.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  const double radius_m = options.fingertip_radius_m;
  double f_alone = 0.0;
  for (int i = 0; i <= 50; ++i) {
    alice.p_WE[0] = Eigen::Vector3d(-0.105, 0.0, 0.02 + radius_m + 0.002 - 1e-4 * std::min(i, 40));
    f_alone = step(r, alice, -100.0 + i);
    ASSERT_EQ(step(oracle, alice, -100.0 + i), f_alone);
  }
  ASSERT_GT(f_alone, 0.05);  // she presses the block

  // Bob presses 5 mm away, 3 mm deep: his set arrives at t0 and is his last.
  const auto bob = BobOnTheBlock;
  const session::PeerContactsConfig fade{200ms, 500ms};
  session::PeerContacts peers(fade);
  peers.Receive(bob(1.0), t0, "alice");

  // The bridge's tick as ReceivePeers runs it (without DDS), at t0 + t_ms.
  auto at = [&](double t_ms) { return t0 + std::chrono::microseconds(static_cast<std::int64_t>(t_ms * 1e3)); };
  auto bridge_tick = [&](double t_ms) {
    peers.Expire(at(t_ms));
    r.SetRemote(ToRemoteContacts(peers, r.models(), at(t_ms)));
  };
  // The oracle's peer: bob's set scaled by the law's weight at t_ms, received just now.
  auto oracle_tick = [&](double t_ms) {
    session::PeerContacts now_peers(fade);
    const double w = now_peers.Weight(at(t_ms) - t0);
    if (w > 0.0) now_peers.Receive(bob(w), at(t_ms), "alice");
    oracle.SetRemote(ToRemoteContacts(now_peers, oracle.models(), at(t_ms)));
  };
  bridge_tick(0.0);
  oracle_tick(0.0);
  const double f_full = step(r, alice, 0.0);
  ASSERT_EQ(step(oracle, alice, 0.0), f_full);
  ASSERT_GT(std::abs(f_full - f_alone), 0.01) << "bob's press must change alice's force to test its fade";

  // 1 ms haptic steps to 600 ms; bridge ticks every 10 ms, none from 250 to 400 ms (stalled).
  double prev = f_full, prev_oracle = f_full;
  double worst = 0.0, worst_at_ms = 0.0, worst_oracle = 0.0, off = 0.0, off_at_ms = 0.0;
  long allocations = 0;  // by the haptic thread's steps (the fade is computed there)
  for (int t = 1; t <= 600; ++t) {
    if (t % 10 == 0 && !(t >= 250 && t < 400)) bridge_tick(t);
    oracle_tick(t);
    const long before = testing::AllocationCount();
    const double now_f = step(r, alice, t);
    allocations += testing::AllocationCount() - before;
    const double now_oracle = step(oracle, alice, t);
    if (std::abs(now_f - prev) > worst) {
      worst = std::abs(now_f - prev);
      worst_at_ms = t;
    }
    worst_oracle = std::max(worst_oracle, std::abs(now_oracle - prev_oracle));
    if (std::abs(now_f - now_oracle) > off) {
      off = std::abs(now_f - now_oracle);
      off_at_ms = t;
    }
    prev = now_f;
    prev_oracle = now_oracle;
  }
  // The same solve with the same inputs: equal but for round-off (1e-9 N, far below a step).
  EXPECT_LE(worst, worst_oracle + 1e-9)
      << "alice's force moved " << worst << " N in one 1 ms step at " << worst_at_ms
      << " ms; a weight falling at the fade's rate moves it at most " << worst_oracle << " N per step";
  EXPECT_LE(off, 1e-9) << "alice's force at " << off_at_ms << " ms is " << off
                       << " N off the force with bob's contact at the fade's weight for that step";
  EXPECT_LT(worst_oracle, 0.02 * std::abs(f_full - f_alone));  // the oracle itself ramps (300 steps)
  EXPECT_NEAR(prev, f_alone, 1e-9);                             // gone at the lifespan
  EXPECT_EQ(allocations, 0);
  std::filesystem::remove_all(dir);
}

// A peer still pressing while this node's bridge stalls past the fade's start: its contact
// fades (its newest set gets old), and when the bridge hands the next set over it comes back
// at the fade's rate, not in one step. Bob presses the block beside alice; the bridge ticks
// every 10 ms with bob's newest set but stalls from 10 to 450 ms (bob's weight falls to 0.17 by
// then: fade 200-500 ms). Before the rise was limited, alice's force stepped back by 83 % of what
// bob's press changes in one haptic step (a 570 ms bridge stall in a loaded run of
// session.vanished_member).
TEST(SceneRenderer, APeerBackAfterABridgeStallComesBackAtTheFadesRate) {
  using namespace std::chrono_literals;
  using Clock = session::PeerContacts::Clock;
  const auto dir = LabDir("return");
  world::SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneRenderer r(scene::LoadScene(WriteLab(dir, kGroundAndBlock)), options);
  r.SetCouplingPassivity(false);  // the fade alone, as in the test above
  const auto t0 = Clock::now();
  auto at = [&](double t_ms) { return t0 + std::chrono::microseconds(static_cast<std::int64_t>(t_ms * 1e3)); };
  std::array<Eigen::Vector3d, kFingers> f{};
  DeviceReading alice;
  alice.valid = true;
  for (auto& p : alice.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  auto step = [&](double t_ms) {
    r.Render(0.0, 1e-3, session::PeerContacts::SteadyNs(at(t_ms)), alice, f);
    return f[0].z();
  };
  double f_alone = 0.0;
  for (int i = 0; i <= 50; ++i) {
    alice.p_WE[0] = Eigen::Vector3d(-0.105, 0.0, 0.02 + options.fingertip_radius_m + 0.002 - 1e-4 * std::min(i, 40));
    f_alone = step(-100.0 + i);
  }
  const session::PeerContactsConfig fade{200ms, 500ms};
  session::PeerContacts peers(fade);
  auto bridge_tick = [&](double t_ms) {
    peers.Receive(BobOnTheBlock(1.0), at(t_ms), "alice");  // bob goes on pressing
    peers.Expire(at(t_ms));
    r.SetRemote(ToRemoteContacts(peers, r.models(), at(t_ms)));
  };
  bridge_tick(0.0);
  const double f_full = step(0.0);
  const double change = std::abs(f_full - f_alone);
  ASSERT_GT(change, 0.01) << "bob's press must change alice's force";
  double prev = f_full, worst = 0.0, worst_at_ms = 0.0, low = f_full;
  long allocations = 0;
  for (int t = 1; t <= 900; ++t) {
    if (t % 10 == 0 && !(t >= 10 && t < 450)) bridge_tick(t);
    const long before = testing::AllocationCount();
    const double now_f = step(t);
    allocations += testing::AllocationCount() - before;
    if (t >= 450 && std::abs(now_f - prev) > worst) {
      worst = std::abs(now_f - prev);
      worst_at_ms = t;
    }
    if (t < 450) low = now_f;
    prev = now_f;
  }
  ASSERT_GT(std::abs(low - f_full), 0.5 * change) << "bob's contact must have faded during the stall";
  // Back at the fade's rate (1 / 0.3 s): the weight moves 1/300 a step; the force, rebuilt from
  // the patch's faded depth, up to 1.5 times the average (the test above), so 2 times is allowed.
  const double bound = 2.0 * change / 300.0;
  EXPECT_LE(worst, bound) << "alice's force moved " << worst << " N in one 1 ms step at " << worst_at_ms
                          << " ms as bob's contact came back (allowed " << bound << " N)";
  EXPECT_NEAR(prev, f_full, 1e-9) << "back at full weight 450 ms after the bridge resumed";
  EXPECT_EQ(allocations, 0);
  std::filesystem::remove_all(dir);
}

// The ground-and-block lab's renderer with the bridge's wake-up set, and a hand (every fingertip
// far from everything) stepped through it 1 ms at a time, counting the steps' heap allocations.
struct WokenLab {
  explicit WokenLab(const std::string& name) : dir(LabDir(name)), options(OptionsIn(dir)) {
    renderer.SetWakeup(wake);
    hand.valid = true;
    for (auto& p : hand.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  }
  ~WokenLab() { std::filesystem::remove_all(dir); }
  void Step() {
    t_ns += 1'000'000;
    const long before = testing::AllocationCount();
    renderer.Render(0.0, 1e-3, t_ns, hand, f);
    allocations += testing::AllocationCount() - before;
  }
  static world::SceneModelsOptions OptionsIn(const std::filesystem::path& dir) {
    world::SceneModelsOptions o;
    o.cache_dir = dir / "cache";
    return o;
  }
  std::filesystem::path dir;
  world::SceneModelsOptions options;
  SceneRenderer renderer{scene::LoadScene(WriteLab(dir, kGroundAndBlock)), options};
  std::shared_ptr<common::Wakeup> wake = std::make_shared<common::Wakeup>();
  DeviceReading hand;
  std::array<Eigen::Vector3d, kFingers> f{};
  std::uint64_t t_ns = common::SteadyNowNs();
  long allocations = 0;
};

// What a screen shows of a hand: with the motion wake on, the step after the one that moved the
// hand (its base or a fingertip it has) half a millimetre past the last post posts the bridge's
// wake-up, no sooner than the gap after the last post, without allocating; a hand at rest, a
// finger the device lacks, or the wake off posts nothing.
TEST(SceneRenderer, AHandThatMovesWakesTheBridgeTheStepAfter) {
  WokenLab lab("motion");
  SceneRenderer& r = lab.renderer;
  const std::shared_ptr<common::Wakeup>& wake = lab.wake;
  DeviceReading& hand = lab.hand;
  hand.p_WH = Eigen::Vector3d(1.0, 1.0, 1.2);  // far from everything, as the fingertips
  const long& allocations = lab.allocations;
  auto step = [&] { lab.Step(); };
  auto move_base = [&](double dx_m) {
    hand.p_WH.x() += dx_m;
    for (auto& p : hand.p_WE) p.x() += dx_m;
  };
  for (int i = 0; i < 10; ++i) {
    move_base(2e-3);
    step();
  }
  EXPECT_EQ(wake->posts(), 0u) << "the motion wake is off by default";
  EXPECT_FALSE(r.TakeMotion());

  const std::uint64_t gap_ns = 10'000'000;
  r.SetMotionWake(0.5e-3, gap_ns);
  step();
  EXPECT_EQ(wake->posts(), 0u) << "the first step's state is not out yet";
  step();
  ASSERT_EQ(wake->posts(), 1u) << "the hand's first state once the wake is on";
  EXPECT_TRUE(r.TakeMotion());
  EXPECT_FALSE(r.TakeMotion()) << "taken once";
  for (int i = 0; i < 30; ++i) step();
  EXPECT_EQ(wake->posts(), 1u) << "a hand at rest";
  EXPECT_FALSE(r.TakeMotion());

  // 0.09 mm a step: the step that passes 0.5 mm moves it; the one after posts.
  int steps = 0;
  while (wake->posts() == 1u && steps < 20) {
    move_base(0.9e-4);
    step();
    ++steps;
  }
  EXPECT_EQ(steps, 7) << "posted at the step after the sixth 0.09 mm (0.54 mm > 0.5 mm)";
  EXPECT_TRUE(r.TakeMotion());

  // Moving on fast: no post sooner than the gap after the last.
  const std::uint32_t posts = wake->posts();
  for (int i = 0; i < 9; ++i) {
    move_base(1e-3);
    step();
  }
  EXPECT_EQ(wake->posts(), posts) << "within the gap";
  move_base(1e-3);
  step();  // 10 ms after the post: this step moved past the threshold
  move_base(1e-3);
  step();
  EXPECT_EQ(wake->posts(), posts + 1) << "the gap passed";
  EXPECT_TRUE(r.TakeMotion());

  // One fingertip closing alone wakes it; a finger the device lacks does not.
  for (int i = 0; i < 20; ++i) step();
  const std::uint32_t still = wake->posts();
  hand.finger_mask = 0b00011;  // thumb and index only
  hand.p_WE[4].z() -= 5e-3;
  for (int i = 0; i < 3; ++i) step();
  EXPECT_EQ(wake->posts(), still) << "the little finger is not this device's";
  hand.p_WE[1].z() -= 1e-3;
  step();
  step();
  EXPECT_EQ(wake->posts(), still + 1) << "the index fingertip moved 1 mm";
  EXPECT_TRUE(r.TakeMotion());

  r.SetMotionWake(0.0, gap_ns);
  for (int i = 0; i < 20; ++i) {
    move_base(1e-3);
    step();
  }
  EXPECT_EQ(wake->posts(), still + 1) << "the motion wake turned off";
  EXPECT_EQ(allocations, 0);
}

// The coupling path between ticks: the haptic step posts the bridge's wake-up when a finger
// starts or stops touching an object, and after every step while the bridge asks for it (a
// peer shares the object), without allocating; a report with nothing new posts nothing.
TEST(SceneRenderer, TheStepWakesTheBridgeForAReportWorthOffering) {
  WokenLab lab("wake");
  SceneRenderer& r = lab.renderer;
  const std::shared_ptr<common::Wakeup>& wake = lab.wake;
  DeviceReading& hand = lab.hand;
  // The index fingertip 2 mm above the block's top (z = 0.02 m).
  const double above_m = 0.02 + lab.options.fingertip_radius_m + 0.002;
  hand.p_WE[0] = Eigen::Vector3d(-0.1, 0.0, above_m);
  const long& allocations = lab.allocations;
  auto step = [&] { lab.Step(); };
  for (int i = 0; i < 5; ++i) step();
  EXPECT_EQ(wake->posts(), 0u) << "no finger touches anything: nothing to offer";
  // It comes down 0.1 mm a step: the step that touches posts, none before.
  ContactReport report;
  int down = 0;
  for (; down < 40 && wake->posts() == 0; ++down) {
    hand.p_WE[0].z() = above_m - 1e-4 * (down + 1);
    step();
  }
  ASSERT_EQ(wake->posts(), 1u) << "the touch began";
  EXPECT_GE(down, 15) << "posted before the fingertip reached the block";
  EXPECT_TRUE(wake->WaitUntil(common::Wakeup::Clock::now()));
  ASSERT_TRUE(r.TakeReport(report));
  EXPECT_GE(report.fingers[0].object, 0);
  for (int i = 0; i < 5; ++i) step();
  EXPECT_EQ(wake->posts(), 1u) << "still touching, no peer on the object: the bridge's tick will do";
  r.SetReportWake(true);  // a peer's loop solves the block with this hand's contacts
  for (int i = 0; i < 5; ++i) step();
  EXPECT_EQ(wake->posts(), 6u) << "every step's report goes to the deadband";
  r.SetReportWake(false);
  hand.p_WE[0] = Eigen::Vector3d(1.0, 1.0, 1.0);
  step();
  EXPECT_EQ(wake->posts(), 7u) << "the touch ended";
  EXPECT_EQ(allocations, 0);
}

// While a peer shares the block, the step wakes the bridge only for a report whose contact set
// the deadband may send (WorthAWakeUp against the set the bridge last sent): the index fingertip
// goes down into the block and wanders in depth and along the surface at random, with stretches
// held still. The oracle is the bridge's own path run beside it (ToContactSet -> the real
// ContactSetDeadband at its defaults): every set the deadband sends for a perceptible change
// was posted by its step (keepalives are the bridge's ticks'). Before, the step posted after
// every step while the peer shared the object; a still press now posts nothing.
TEST(SceneRenderer, ASharedPressWakesTheBridgeOnlyForAReportTheDeadbandMaySend) {
  WokenLab lab("spare");
  SceneRenderer& r = lab.renderer;
  const std::shared_ptr<common::Wakeup>& wake = lab.wake;
  DeviceReading& hand = lab.hand;
  const double top_m = 0.02 + lab.options.fingertip_radius_m;  // the fingertip's centre touching the top
  hand.p_WE[1] = Eigen::Vector3d(-0.1, 0.0, top_m + 0.002);
  for (int i = 0; i < 5; ++i) lab.Step();
  r.SetReportWake(true);  // a peer's loop solves the block with this hand's contacts
  session::ContactSetDeadband deadband;
  msg::ContactSet set;
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  double depth_m = -0.002, x_m = -0.1, speed = 0.0;
  int steps = 0, posted = 0, sent = 0, sent_perceptible = 0, missed = 0, held_posts = 0, held_steps = 0;
  for (int i = 0; i < 4000; ++i) {
    // Every 200 steps a new stretch: held still, or moving at up to 2 mm/s in depth.
    if (i % 200 == 0) speed = (i / 200) % 2 == 0 ? 0.0 : 2e-3 * unit(rng);
    const bool held = i >= 200 && speed == 0.0;
    depth_m = std::clamp(depth_m + (i < 200 ? 2.5e-5 : speed * 1e-3), 0.0005, 0.004);
    if (i < 200) depth_m = std::min(depth_m, -0.002 + 2.5e-5 * (i + 1));
    if (!held && i >= 200) x_m = std::clamp(x_m + 1e-6 * unit(rng), -0.105, -0.095);
    hand.p_WE[1] = Eigen::Vector3d(x_m, 0.0, top_m - depth_m);
    const std::uint64_t before = wake->posts();
    lab.Step();
    while (wake->WaitUntil(common::Wakeup::Clock::now())) {
    }
    const bool step_posted = wake->posts() > before;
    ContactReport report;
    ASSERT_TRUE(r.TakeReport(report));
    ++steps;
    posted += step_posted;
    if (held) {
      ++held_steps;
      held_posts += step_posted;
    }
    ToContactSet(report, r.models(), -1, lab.options.fingertip_radius_m, set);
    session::DeadbandReason why = session::DeadbandReason::kNone;
    if (!deadband.Offer(set, report.step_ns, &why)) continue;
    ++sent;
    if (why != session::DeadbandReason::kKeepalive) {
      ++sent_perceptible;
      if (!step_posted) ++missed;
    }
    r.SetSentReference(ToSentReference(report, set, -1, deadband.config(), report.step_ns));
  }
  std::printf("posted after %d of %d steps (%d of %d held still); the deadband sent %d sets, %d for a perceptible "
              "change\n", posted, steps, held_posts, held_steps, sent, sent_perceptible);
  EXPECT_EQ(missed, 0) << "of " << sent_perceptible << " sets sent for a perceptible change";
  EXPECT_GT(sent_perceptible, 20) << "the wandering press changed perceptibly now and then";
  EXPECT_LT(posted, steps / 4) << "posts of " << steps << " steps (before: every step)";
  EXPECT_GT(held_steps, 500);
  EXPECT_LE(held_posts, held_steps / 50) << "a press held still wakes (almost) nothing";
  EXPECT_GT(r.wakes_spared(), 0u);
  EXPECT_EQ(lab.allocations, 0);
}

// --dump-deformation: the haptic thread's snapshot of its solve's loads, turned into a field by
// the bridge's LocalFieldDump, is the field of the solve itself (the contact solver's own
// SurfaceDisplacements, in the object's frame turned into W), at every node; and where the
// fingertip presses the body moves by about the fingertip's depth.
TEST(SceneRenderer, TheDumpedFieldIsTheFieldOfItsOwnSolve) {
  const auto dir = LabDir("dump");
  const auto file = WriteLab(dir, R"(
      {"id": "block", "kind": "deformable", "shape": "box", "position_m": [-0.1, 0, 0.01],
       "orientation_wxyz": [0.9238795, 0, 0, 0.3826834],
       "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.4}, "fixed": {"below_m": -0.0099}})");
  world::SceneModelsOptions options;
  options.cache_dir = dir / "cache";
  SceneRenderer r(scene::LoadScene(file), options);
  r.EnableLoadSnapshots();
  DeviceReading alice;
  alice.valid = true;
  for (auto& p : alice.p_WE) p = Eigen::Vector3d(1.0, 1.0, 1.0);
  std::array<Eigen::Vector3d, kFingers> f{};
  for (int i = 0; i < 2 * DeformableLoads::kEverySteps; ++i) {  // 2 mm into the block's top
    alice.p_WE[0] = Eigen::Vector3d(-0.1, 0.003, 0.02 + options.fingertip_radius_m - 1e-4 * std::min(i, 20));
    r.Render(0.0, 1e-3, 1'000'000ull * static_cast<std::uint64_t>(i + 1), alice, f);
  }
  ASSERT_GT(f[0].z(), 0.05);  // she presses it
  LocalFieldDump dump(dir / "dump", "alice", std::chrono::milliseconds(100));
  dump.Update(r);
  ASSERT_EQ(dump.written(), 1u);
  std::ifstream in(dir / "dump" / "block.json");
  const nlohmann::json j = nlohmann::json::parse(in);
  EXPECT_EQ(j["object"], "block");
  EXPECT_EQ(j["user"], "alice");

  const contact::ObjectId block = r.models().Find("block");
  const contact::HapticWorld& world = *r.models().world;
  const fem::ContactSolver* solver = world.contact_solver(block);
  ASSERT_NE(solver, nullptr);
  const auto& prepared = r.models().deformables[0];
  std::vector<Eigen::Vector3d> u(static_cast<std::size_t>(prepared.compliance->num_nodes()));
  ASSERT_TRUE(solver->SurfaceDisplacements(u));
  const Eigen::Matrix3d R = world.pose(block).linear();
  double largest = 0.0;
  int compared = 0;
  for (std::size_t s = 0; s < u.size(); ++s) {
    const std::string node = std::to_string(prepared.compliance->nodes()[s]);
    const Eigen::Vector3d want = R * u[s];
    if (!j["u_W_m"].contains(node)) {
      EXPECT_EQ(want.squaredNorm(), 0.0) << node;
      continue;
    }
    const auto& got = j["u_W_m"][node];
    const Eigen::Vector3d g(got[0].get<double>(), got[1].get<double>(), got[2].get<double>());
    EXPECT_LE((g - want).norm(), 1e-9 * (1.0 + want.norm()) + 1e-12) << node;  // 9 printed digits
    largest = std::max(largest, g.norm());
    ++compared;
  }
  EXPECT_GT(compared, 20);
  // Under the fingertip the solve imposed the sphere's indentation, delta - r^2 / 2R along -n
  // at a patch node r from the contact point (docs/fem.md): the dumped field has it there.
  const contact::FingerResult& tip = world.fingers()[0];
  ASSERT_GE(tip.main_node, 0);
  EXPECT_GT(tip.depth_m, 1e-3);
  const Eigen::Vector3d p_node = world.pose(block) * prepared.mesh->positions_m()[static_cast<std::size_t>(tip.main_node)];
  const double r_m = (p_node - tip.p_WC_m).norm();
  const double indent = tip.depth_m - r_m * r_m / (2.0 * options.fingertip_radius_m);
  const auto& at = j["u_W_m"][std::to_string(tip.main_node)];
  const Eigen::Vector3d u_main(at[0].get<double>(), at[1].get<double>(), at[2].get<double>());
  EXPECT_NEAR(-u_main.dot(tip.n_W), indent, 1e-3 * indent) << "r " << r_m;
  EXPECT_LE(largest, tip.depth_m);
  // A folder that cannot be made is named.
  try {
    LocalFieldDump bad("/proc/handshare_no_such_dir/x", "alice", std::chrono::milliseconds(100));
    ADD_FAILURE() << "no error for an impossible folder";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/handshare_no_such_dir/x"), std::string::npos) << e.what();
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace handshare::haptic
