// The haptic node's conversions between DDS samples and the haptic world's types, without a
// participant: the message types are plain generated classes.
#include "bridge_conversions.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "handshare/dds/sample_checks.hpp"
#include "handshare/scene/scene.hpp"

namespace handshare::haptic {
namespace {

// A small world: a static table, a dynamic ball, a soft block (deformable, FEM).
class BridgeConversions : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    // One folder per process: ctest runs the tests of this suite in parallel processes.
    dir_ = new std::filesystem::path(std::filesystem::temp_directory_path() /
                                     ("handshare_bridge_conversions_" + std::to_string(getpid())));
    std::filesystem::remove_all(*dir_);
    std::filesystem::create_directories(*dir_ / "scenes");
    const auto file = *dir_ / "scenes" / "lab.json";
    std::ofstream(file) << R"({"name": "lab", "gravity_m_per_s2": [0, 0, -9.81], "objects": [
        {"id": "ground", "kind": "rigid", "shape": "box", "position_m": [0, 0, -0.02], "half_extent_m": [0.3, 0.3, 0.02]},
        {"id": "ball", "kind": "rigid", "shape": "sphere", "position_m": [0.1, 0, 0.04], "radius_m": 0.04, "mass_kg": 0.2},
        {"id": "block", "kind": "deformable", "shape": "box", "position_m": [-0.1, 0, 0.01],
         "half_extent_m": [0.02, 0.02, 0.01], "material": {"E_Pa": 20000, "nu": 0.4}, "fixed": {"below_m": -0.0099}}],
        "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
    world::SceneModelsOptions options;
    options.cache_dir = *dir_ / "cache";
    models_ = new world::SceneModels(world::BuildSceneModels(scene::LoadScene(file), options));
  }
  static void TearDownTestSuite() {
    delete models_;
    std::filesystem::remove_all(*dir_);
    delete dir_;
  }
  static const world::SceneModels& models() { return *models_; }

  static msg::ObjectState Body(const std::string& id, const std::string& owner, double x) {
    msg::ObjectState s;
    s.object_id(id);
    s.owner(owner);
    s.p_WO_m({x, 0.0, 0.05});
    s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
    s.v_WO_m_per_s({0.1, 0.2, 0.3});
    return s;
  }

  static std::filesystem::path* dir_;
  static world::SceneModels* models_;
};
std::filesystem::path* BridgeConversions::dir_ = nullptr;
world::SceneModels* BridgeConversions::models_ = nullptr;

TEST_F(BridgeConversions, DeviceStateCarriesTheSnapshot) {
  HapticSnapshot s;
  s.seq = 42;
  s.stamp_ns = 123456789;
  s.p_WH_m[2] = 0.2;
  s.q_WH_wxyz[0] = 0.5;
  s.p_WE_m[4][1] = -0.03;
  s.f_E_W_N[2][0] = 1.5;
  s.fingertip_radius_m = 0.008;
  s.q_hand_rad[14] = 0.7;
  s.q_arm_rad[5] = -0.4;
  s.fault = true;
  msg::DeviceState m;
  ToDeviceState(s, m);
  EXPECT_EQ(m.q_hand_rad()[14], 0.7);
  EXPECT_EQ(m.q_arm_rad()[5], -0.4);
  EXPECT_EQ(m.seq(), 42u);
  EXPECT_EQ(m.stamp_ns(), 123456789u);
  EXPECT_EQ(m.p_WH_m()[2], 0.2);
  EXPECT_EQ(m.q_WH_wxyz()[0], 0.5);
  EXPECT_EQ(m.p_WE_m()[4][1], -0.03);
  EXPECT_EQ(m.f_E_W_N()[2][0], 1.5);
  EXPECT_EQ(m.fingertip_radius_m(), 0.008);
  EXPECT_TRUE(m.fault());
}

TEST_F(BridgeConversions, LoopStatisticsCarryCountsAndFaults) {
  common::LoopStats s;
  s.rate_Hz = 999.5;
  s.steps = 1000;
  s.overruns = 3;
  s.resyncs = 1;
  msg::LoopStatistics m;
  ToLoopStatistics(s, 7, m);
  EXPECT_EQ(m.rate_Hz(), 999.5);
  EXPECT_EQ(m.steps(), 1000u);
  EXPECT_EQ(m.overruns(), 3u);
  EXPECT_EQ(m.resyncs(), 1u);
  EXPECT_EQ(m.faults(), 7u);
}

TEST_F(BridgeConversions, AHandClaimsTheBodyItGraspsElseTheOneItPushesHardest) {
  const auto ball = models().Find("ball");
  ContactReport r;
  r.num_bodies = 1;
  r.bodies[0].object = ball;
  EXPECT_EQ(ClaimedBody(r), -1);  // no finger on it
  // One finger pushes it: a touch is a claim too.
  r.fingers[1].object = ball;
  r.fingers[1].f_O_N[0] = 1.0;
  EXPECT_EQ(ClaimedBody(r), ball);
  // A finger on another object does not claim the ball.
  ContactReport other;
  other.num_bodies = 1;
  other.bodies[0].object = ball;
  other.fingers[0].object = models().Find("block");
  other.fingers[0].f_O_N[2] = 2.0;
  EXPECT_EQ(ClaimedBody(other), -1);
  // Thumb and index squeeze it from opposite sides: a grasp.
  r.fingers[0].object = ball;
  r.fingers[0].f_O_N[0] = -1.0;
  EXPECT_EQ(ClaimedBody(r), ball);
}

TEST_F(BridgeConversions, AHandFollowsEveryDynamicBodyItDoesNotOwn) {
  ReceivedBodies bodies;
  bodies["ball"] = {Body("ball", "bob", 0.3), 77};
  bodies["ground"] = {Body("ground", "", 0.0), 1};   // static: never followed
  bodies["comet"] = {Body("comet", "", 0.0), 1};     // not in this world
  const FollowedBodies f = ToFollowedBodies(bodies, "alice", models());
  ASSERT_EQ(f.count, 1);
  EXPECT_EQ(f.items[0].object, models().Find("ball"));
  EXPECT_EQ(f.items[0].p_WO_m[0], 0.3);
  EXPECT_EQ(f.items[0].v_WO_m_per_s[2], 0.3);
  EXPECT_EQ(f.items[0].received_ns, 77u);
  EXPECT_EQ(OwnedBody(bodies, "alice", models()), -1);
  // The owner follows nothing: it simulates the ball itself.
  EXPECT_EQ(ToFollowedBodies(bodies, "bob", models()).count, 0);
  EXPECT_EQ(OwnedBody(bodies, "bob", models()), models().Find("ball"));
}

// alice owns the ball and lets go of it while bob's hand grasps it (his contact set says so:
// thumb and index squeeze it from opposite sides). Her node holds the ball still where her hand
// let go of it, at rest, for every tick until the hand-over; a touch of bob's is not a grasp,
// and the hold ends when bob lets go, when her hand grasps again or when she no longer owns it.
TEST_F(BridgeConversions, ABodyLetGoOfWhileAPeerGraspsItIsHeldStillUntilTheHandOver) {
  using Clock = session::PeerContacts::Clock;
  const auto ball = models().Find("ball");
  const auto now = Clock::now();
  msg::ContactSet bob;
  bob.user("bob");
  bob.session("s");
  bob.fingers()[1].active(true);
  bob.fingers()[1].object_id("ball");
  bob.fingers()[1].f_O_N({1.0, 0.0, 0.0});
  session::PeerContacts peers;
  peers.Receive(bob, now, "alice");
  EXPECT_EQ(PeerGrasping(peers, "ball", now), "") << "one finger is a touch";
  bob.fingers()[0].active(true);
  bob.fingers()[0].object_id("ball");
  bob.fingers()[0].f_O_N({-1.0, 0.0, 0.0});
  peers.Receive(bob, now, "alice");
  EXPECT_EQ(PeerGrasping(peers, "ball", now), "bob");
  EXPECT_EQ(PeerGrasping(peers, "block", now), "");
  EXPECT_EQ(PeerGrasping(peers, "ball", now + std::chrono::seconds(1)), "") << "a silent peer's grasp is gone";

  // alice's report: her hand is off the ball, which her node simulates at z = 0.09 m.
  ContactReport r;
  r.num_bodies = 1;
  r.bodies[0].object = ball;
  r.bodies[0].p_WO_m[2] = 0.09;
  r.bodies[0].q_WO_wxyz[0] = 1.0;
  r.bodies[0].v_WO_m_per_s[2] = -0.01;
  HandOverHold hold;
  FollowedBodies followed;
  EXPECT_TRUE(hold.Update(ball, r, "bob", 1000, followed));
  ASSERT_EQ(followed.count, 1);
  EXPECT_EQ(followed.items[0].object, ball);
  EXPECT_EQ(followed.items[0].p_WO_m[2], 0.09);
  EXPECT_EQ(followed.items[0].v_WO_m_per_s[2], 0.0) << "held at rest";
  EXPECT_EQ(followed.items[0].received_ns, 1000u);
  // The next tick: where it was let go, not where the report (now the held pose) drifted.
  r.bodies[0].p_WO_m[2] = 0.0899;
  followed = {};
  EXPECT_FALSE(hold.Update(ball, r, "bob", 2000, followed)) << "the same hold goes on";
  ASSERT_EQ(followed.count, 1);
  EXPECT_EQ(followed.items[0].p_WO_m[2], 0.09);
  EXPECT_EQ(followed.items[0].received_ns, 2000u);
  EXPECT_EQ(hold.holds(), 1u);
  // Her hand grasps it again: she simulates it (nothing followed).
  ContactReport grasping = r;
  grasping.fingers[0] = {.finger = 0, .object = ball};
  grasping.fingers[0].f_O_N[0] = 1.0;
  grasping.fingers[1] = {.finger = 1, .object = ball};
  grasping.fingers[1].f_O_N[0] = -1.0;
  ASSERT_TRUE(HandGrasps(grasping, ball));
  followed = {};
  EXPECT_FALSE(hold.Update(ball, grasping, "bob", 3000, followed));
  EXPECT_EQ(followed.count, 0);
  EXPECT_EQ(hold.held(), -1);
  // bob lets go (no grasper), or the hand-over came (alice owns nothing): no hold.
  EXPECT_FALSE(hold.Update(ball, r, "", 4000, followed));
  EXPECT_FALSE(hold.Update(-1, r, "bob", 5000, followed));
  EXPECT_EQ(followed.count, 0);
  EXPECT_EQ(hold.holds(), 1u);
}

TEST_F(BridgeConversions, TheContactSetNamesObjectsAndReportsTheSimulatedBody) {
  const auto ball = models().Find("ball");
  const auto block = models().Find("block");
  ContactReport r;
  msg::ContactSet m;
  EXPECT_FALSE(ToContactSet(r, models(), -1, 0.008, m));  // nothing touched: nothing to say
  r.fingers[2].object = block;
  r.fingers[2].node = 17;
  r.fingers[2].u_O_m[2] = -0.002;
  r.fingers[2].depth_m = 0.002;
  EXPECT_TRUE(ToContactSet(r, models(), -1, 0.008, m));
  EXPECT_TRUE(m.fingers()[2].active());
  EXPECT_EQ(m.fingers()[2].object_id().to_string(), "block");
  EXPECT_EQ(m.fingers()[2].surface_node(), 17);
  EXPECT_EQ(m.fingers()[2].u_O_m()[2], -0.002);
  EXPECT_EQ(m.fingers()[2].radius_m(), 0.008);
  EXPECT_FALSE(m.fingers()[0].active());
  EXPECT_EQ(m.fingers()[0].object_id().to_string(), "");
  EXPECT_FALSE(m.simulating());
  // The owner of the ball keeps reporting its pose after letting go: still something to say.
  ContactReport owner;
  owner.num_bodies = 1;
  owner.bodies[0].object = ball;
  owner.bodies[0].p_WO_m[2] = 0.3;
  owner.bodies[0].v_WO_m_per_s[0] = 0.4;
  EXPECT_TRUE(ToContactSet(owner, models(), ball, 0.008, m));
  EXPECT_TRUE(m.simulating());
  EXPECT_EQ(m.simulated_object_id().to_string(), "ball");
  EXPECT_EQ(m.p_WO_m()[2], 0.3);
  EXPECT_EQ(m.v_WO_m_per_s()[0], 0.4);
  EXPECT_EQ(m.grasped_object_id().to_string(), "");
}

// A fingertip pushed 11.7 cm into the ball (the tour once sent this after a stall): every
// receiver dropped the whole set. It goes out clamped to what receivers accept, same direction.
TEST_F(BridgeConversions, ADepthBeyondWhatReceiversAcceptGoesOutClamped) {
  ContactReport r;
  r.fingers[0].object = models().Find("block");
  r.fingers[0].n_O[2] = 1.0;
  r.fingers[0].depth_m = 0.117;
  r.fingers[0].u_O_m[2] = -0.117;
  r.fingers[0].u_O_m[0] = 0.05;
  msg::ContactSet m;
  ASSERT_TRUE(ToContactSet(r, models(), -1, 0.008, m));
  m.session("s");
  m.user("alice");
  EXPECT_EQ(dds::CheckContactSet(m, "s", dds::SampleBounds{}), "");
  EXPECT_DOUBLE_EQ(m.fingers()[0].depth_m(), 0.1);
  const auto& u = m.fingers()[0].u_O_m();
  EXPECT_NEAR(std::sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]), 0.1, 1e-12);
  EXPECT_NEAR(u[0] / u[2], 0.05 / -0.117, 1e-12);
  r.fingers[0].depth_m = -0.2;  // a gap, the same
  ASSERT_TRUE(ToContactSet(r, models(), -1, 0.008, m));
  EXPECT_DOUBLE_EQ(m.fingers()[0].depth_m(), -0.1);
}

TEST_F(BridgeConversions, PeersReachTheRendererOnlyOnDeformables) {
  using Clock = session::PeerContacts::Clock;
  const auto now = Clock::now();
  msg::ContactSet bob;
  bob.user("bob");
  bob.session("s");
  bob.fingers()[0].active(true);
  bob.fingers()[0].object_id("block");
  bob.fingers()[0].u_O_m({0.0, 0.0, -0.001});
  bob.fingers()[1].active(true);
  bob.fingers()[1].object_id("ball");   // a rigid body moves by its owner's pose instead
  bob.fingers()[2].active(true);
  bob.fingers()[2].object_id("comet");  // not in this world
  session::PeerContacts peers;
  peers.Receive(bob, now, "alice");
  RemoteContacts remote = ToRemoteContacts(peers, models(), now);
  ASSERT_EQ(remote.count, 1);
  EXPECT_EQ(remote.items[0].contact.object, models().Find("block"));
  EXPECT_EQ(remote.items[0].contact.finger, 0);
  EXPECT_EQ(remote.items[0].contact.u_O_m[2], -0.001);
  EXPECT_EQ(remote.items[0].received_ns, session::PeerContacts::SteadyNs(now));
  // Fading at the bridge's tick: handed over as received, with the fade law, for the haptic
  // thread to fade at each of its steps.
  remote = ToRemoteContacts(peers, models(), now + std::chrono::milliseconds(350));
  ASSERT_EQ(remote.count, 1);
  EXPECT_EQ(remote.items[0].contact.u_O_m[2], -0.001);
  EXPECT_EQ(remote.fade.fade_after_ns, peers.fade().fade_after_ns);
  EXPECT_EQ(remote.fade.lifespan_ns, peers.fade().lifespan_ns);
  // Silent for longer than the lifespan: gone.
  remote = ToRemoteContacts(peers, models(), now + std::chrono::seconds(1));
  EXPECT_EQ(remote.count, 0);
}

TEST_F(BridgeConversions, PoseOfNormalizesTheQuaternion) {
  ContactReport::Body b;
  b.q_WO_wxyz[0] = 2.0;  // not unit
  b.p_WO_m[1] = 0.25;
  const Eigen::Isometry3d X = PoseOf(b);
  EXPECT_TRUE(X.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-12));
  EXPECT_EQ(X.translation().y(), 0.25);
}

}  // namespace
}  // namespace handshare::haptic
