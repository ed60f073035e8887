// ObjectAuthority hand-over of a rigid body: the owner reports the ball's pose and velocity while
// it holds it; when it lets go and the server frees the ball, the server simulates the ball on
// from there with that velocity (it used to restart from rest, stopping in mid-air).
#include "handshare/world_server/object_authority.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <memory>
#include <thread>

#include "handshare/session/contact_deadband.hpp"
#include "server_conversions.hpp"
#include "test_support.hpp"

namespace handshare::server {
namespace {

using Clock = ObjectAuthority::Clock;
constexpr double kMoon = 1.62;

msg::ContactSet OwnerSet(const std::string& grasped, const Eigen::Vector3d& p, const Eigen::Vector3d& v) {
  msg::ContactSet s;
  s.session("s");
  s.user("alice");
  s.grasped_object_id(grasped);
  s.simulating(true);  // an owner keeps reporting its body until the server frees it
  s.simulated_object_id("ball");
  for (int k = 0; k < 3; ++k) {
    s.p_WO_m()[k] = p[k];
    s.v_WO_m_per_s()[k] = v[k];
  }
  s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  return s;
}

// A tick's body states as the publisher writes them (ToObjectState, the DDS conversion).
std::vector<msg::ObjectState> Published(const TickOutput& out) {
  std::vector<msg::ObjectState> states;
  for (const auto& body : out.bodies) states.push_back(ToObjectState(body, "s", 0));
  return states;
}

// The ball's published state in `out`, or nullptr when the tick did not publish it. Valid until
// the next call.
const msg::ObjectState* BallState(const TickOutput& out) {
  static std::vector<msg::ObjectState> published;
  published = Published(out);
  for (const auto& st : published) {
    if (st.object_id().to_string() == "ball") return &st;
  }
  return nullptr;
}

// The scene of these tests: testing::WriteBallScene (a ground box and a 0.2 kg ball of radius
// 4 cm resting on it).
using testing::WriteBallScene;

// Ticks every 10 ms (sleeping as long, for the loader thread) until the models are adopted;
// `each` sees every tick's output. Returns the tick time reached.
Clock::time_point TickUntilReady(ObjectAuthority& world, Clock::time_point now,
                                 const std::function<void(const TickOutput&)>& each = nullptr) {
  const auto dt = std::chrono::milliseconds(10);
  for (int i = 0; i < 2000 && !world.ready(); ++i) {
    std::this_thread::sleep_for(dt);
    now += dt;
    const TickOutput out = world.Tick(now, 0.01);
    if (each) each(out);
  }
  return now;
}

// An ObjectAuthority of session "s" on the Moon with the ball scene, its models adopted at now_.
class BallOnTheMoon : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto file = WriteBallScene(dir_.path(), "moon", -kMoon);
    ObjectAuthorityOptions options;
    options.models.cache_dir = dir_.path() / "cache";
    world_ = std::make_unique<ObjectAuthority>("s", options);
    world_->SetScene(scene::LoadScene(file));
    now_ = TickUntilReady(*world_, Clock::now());
    ASSERT_TRUE(world_->ready());
  }
  static constexpr std::chrono::milliseconds kDt{10};
  testing::TempDir dir_;
  std::unique_ptr<ObjectAuthority> world_;
  Clock::time_point now_;
};

TEST_F(BallOnTheMoon, ALetGoBallFliesOnWithTheOwnersVelocity) {
  ObjectAuthority& world = *world_;
  const auto dt = kDt;
  Clock::time_point now = now_;

  // alice holds the ball and carries it up and sideways: 0.4 m/s in x, 0.6 m/s up.
  const Eigen::Vector3d v(0.4, 0.0, 0.6);
  Eigen::Vector3d p(0.0, 0.0, 0.15);
  for (int i = 0; i < 10; ++i) {
    now += dt;
    p += 0.01 * v;
    world.OnContactSet(OwnerSet("ball", p, v), now);
    world.Tick(now, 0.01);
  }
  ASSERT_EQ(world.owner("ball"), "alice");
  // She lets go (no grasp claim) and keeps reporting the body it simulates until the server
  // frees it (release grace 100 ms); her ball moves on ballistically meanwhile.
  Eigen::Vector3d vb = v;
  int ticks_to_free = 0;
  while (!world.owner("ball").empty()) {
    ASSERT_LT(++ticks_to_free, 50);
    now += dt;
    p += 0.01 * vb;
    vb.z() -= kMoon * 0.01;
    world.OnContactSet(OwnerSet("", p, vb), now);
    world.Tick(now, 0.01);
  }
  // Free: the server simulates it. Over the next 0.1 s it goes on at (0.4, 0, ~0.6 - g t).
  const Eigen::Vector3d p_free = p;
  Eigen::Vector3d last_p = p_free, last_v = Eigen::Vector3d::Zero();
  for (int i = 0; i < 10; ++i) {
    now += dt;
    const TickOutput out = world.Tick(now, 0.01);
    const msg::ObjectState* st = BallState(out);
    ASSERT_NE(st, nullptr) << "a flying free ball is published every tick";
    EXPECT_EQ(st->owner().to_string(), "");
    last_p = Eigen::Vector3d(st->p_WO_m()[0], st->p_WO_m()[1], st->p_WO_m()[2]);
    last_v = Eigen::Vector3d(st->v_WO_m_per_s()[0], st->v_WO_m_per_s()[1], st->v_WO_m_per_s()[2]);
  }
  // 0.1 s of free flight on the Moon from (p_free, vb): ballistic, less the scene bodies' light
  // air damping (about 2% of the speed in 0.1 s). Restarting from rest instead would give
  // v_x = 0 and a ball falling from p_free.
  const Eigen::Vector3d expected = p_free + 0.1 * vb - Eigen::Vector3d(0, 0, 0.5 * kMoon * 0.01);
  EXPECT_LT((last_p - expected).norm(), 1e-3) << last_p.transpose() << " vs " << expected.transpose();
  EXPECT_GT(last_p.z(), p_free.z() + 0.02);  // still rising: it did not stop in mid-air
  EXPECT_NEAR(last_v.x(), 0.4, 0.4 * 0.03);
  EXPECT_NEAR(last_v.z(), vb.z() - kMoon * 0.1, 0.02);
}

// A hand-over: bob grasps the ball alice holds, alice lets go, the server hands it to bob
// (release grace 100 ms). Until bob's node simulates it (its first set saying so comes a round
// trip later: 100 ms at 50 ms each way), the ball is in bob's grasp: the server holds it where
// alice left it, at rest, instead of letting it fall there (8 mm in 0.1 s on the Moon), and
// publishes it there as bob's. Then bob's pose is the one published.
TEST_F(BallOnTheMoon, AHandedOverBodyStaysWhereItsLastOwnerLeftItUntilTheNewOwnerSimulatesIt) {
  ObjectAuthority& world = *world_;
  const auto dt = kDt;
  Clock::time_point now = now_;
  const Eigen::Vector3d p(0.0, 0.0, 0.15), rest = Eigen::Vector3d::Zero();
  msg::ContactSet bob;
  bob.session("s");
  bob.user("bob");
  bob.grasped_object_id("ball");
  bob.simulating(false);
  for (int i = 0; i < 10; ++i) {
    now += dt;
    world.OnContactSet(OwnerSet("ball", p, rest), now);
    if (i >= 5) world.OnContactSet(bob, now);
    world.Tick(now, 0.01);
  }
  ASSERT_EQ(world.owner("ball"), "alice");
  // alice lets go; her node holds the ball still while bob grasps it and reports it so.
  bool handed = false;
  for (int i = 0; i < 50 && !handed; ++i) {
    now += dt;
    world.OnContactSet(OwnerSet("", p, rest), now);
    world.OnContactSet(bob, now);
    const TickOutput out = world.Tick(now, 0.01);
    for (const auto& c : out.ownership) handed |= c.reason == OwnershipReason::kHandedOver && c.owner == "bob";
  }
  ASSERT_TRUE(handed);
  // The round trip to bob's node: alice's node follows now (no longer simulating), bob's sets
  // still claim without simulating.
  msg::ContactSet alice_follows = OwnerSet("", p, rest);
  alice_follows.simulating(false);
  alice_follows.simulated_object_id("");
  for (int i = 0; i < 10; ++i) {
    now += dt;
    world.OnContactSet(alice_follows, now);
    world.OnContactSet(bob, now);
    const TickOutput out = world.Tick(now, 0.01);
    const msg::ObjectState* st = BallState(out);
    ASSERT_NE(st, nullptr) << "a granted body is published every tick until its owner takes it over";
    EXPECT_EQ(st->owner().to_string(), "bob");
    const Eigen::Vector3d got(st->p_WO_m()[0], st->p_WO_m()[1], st->p_WO_m()[2]);
    const Eigen::Vector3d v(st->v_WO_m_per_s()[0], st->v_WO_m_per_s()[1], st->v_WO_m_per_s()[2]);
    EXPECT_LT((got - p).norm(), 1e-9) << "tick " << i << ": " << got.transpose();
    EXPECT_LT(v.norm(), 1e-9) << "tick " << i << ": " << v.transpose();
  }
  // bob's node simulates it now: his pose is published.
  const Eigen::Vector3d p_bob(0.0, 0.0, 0.152);
  msg::ContactSet bob_owns = OwnerSet("ball", p_bob, rest);
  bob_owns.user("bob");
  now += dt;
  world.OnContactSet(bob_owns, now);
  const msg::ObjectState* st = nullptr;
  const TickOutput out = world.Tick(now, 0.01);
  st = BallState(out);
  ASSERT_NE(st, nullptr);
  EXPECT_EQ(st->owner().to_string(), "bob");
  EXPECT_NEAR(st->p_WO_m()[2], p_bob.z(), 1e-9);
}

// The owner's deadband sends a carried body's pose only when it leaves the receivers'
// reckoning (session/contact_deadband.hpp). Between two sets the server publishes the body
// moved on at the set's velocity, for at most session::kMaxReckoning_s: not held still at the
// set's pose (a stair step at 10 Hz for every spectator), nor flown away when sets stop.
TEST_F(BallOnTheMoon, AnOwnersBodyIsReckonedForwardBetweenItsSets) {
  ObjectAuthority& world = *world_;
  const auto dt = kDt;
  Clock::time_point now = now_;
  const Eigen::Vector3d v(0.2, 0.0, 0.1), p0(0.0, 0.0, 0.15);
  now += dt;
  world.OnContactSet(OwnerSet("ball", p0, v), now);
  const Clock::time_point sent = now;
  world.Tick(now, 0.01);
  ASSERT_EQ(world.owner("ball"), "alice");
  for (int i = 1; i <= 40; ++i) {  // 0.4 s without a set
    now += dt;
    const msg::ObjectState* st = nullptr;
    const TickOutput out = world.Tick(now, 0.01);
    st = BallState(out);
    ASSERT_NE(st, nullptr);
    const double age_s = std::chrono::duration<double>(now - sent).count();
    const Eigen::Vector3d expected = p0 + v * std::min(age_s, session::kMaxReckoning_s);
    const Eigen::Vector3d got(st->p_WO_m()[0], st->p_WO_m()[1], st->p_WO_m()[2]);
    EXPECT_LT((got - expected).norm(), 1e-9) << "at " << age_s << " s: " << got.transpose();
  }
}

}  // namespace
}  // namespace handshare::server

namespace handshare::server {
namespace {

// A world change that arrives while the models of the previous world are still being built
// (tetgen and a compliance precompute take seconds): the server neither waits for that build
// (its tick goes on) nor ever adopts it; the newest world's models are the ones adopted.
TEST(ObjectAuthority, AWorldChangeWhileAModelBuildIsInFlightSupersedesIt) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir.path() / "scenes");
  const auto soft = dir.path() / "scenes" / "soft.json";
  std::ofstream(soft) << R"({"name": "soft", "gravity_m_per_s2": [0, 0, -9.81], "objects": [
      {"id": "block", "kind": "deformable", "shape": "box", "position_m": [0, 0, 0.02],
       "half_extent_m": [0.03, 0.03, 0.015], "material": {"E_Pa": 20000, "nu": 0.4}, "fixed": {"below_m": -0.0149}}],
      "messages": [{"language": "en", "text": "t", "next_action": "a"}]})";
  const auto moon = WriteBallScene(dir.path(), "moon", -kMoon);
  ObjectAuthorityOptions options;
  options.models.cache_dir = dir.path() / "cache";  // empty: the soft block is tetrahedralized and precomputed
  ObjectAuthority world("s", options);
  world.SetScene(scene::LoadScene(soft));
  world.SetScene(scene::LoadScene(moon));  // at once: the soft world's build is in flight
  EXPECT_EQ(world.superseded_builds(), 1u);
  EXPECT_FALSE(world.ready());

  std::vector<std::string> notes;
  Clock::time_point now = Clock::now();
  const auto dt = std::chrono::milliseconds(10);
  for (int i = 0; i < 6000 && (!world.ready() || world.superseded_builds() > 0); ++i) {
    std::this_thread::sleep_for(dt);
    now += dt;
    TickOutput out = world.Tick(now, 0.01);
    EXPECT_TRUE(out.deformations.empty()) << "the soft world's block was published";
    for (auto& n : out.notes) notes.push_back(n);
  }
  ASSERT_TRUE(world.ready());
  EXPECT_EQ(world.ready_scene(), "moon");
  EXPECT_EQ(world.superseded_builds(), 0u);
  bool dropped = false;
  for (const auto& n : notes) {
    EXPECT_EQ(n.find("models of 'soft' ready"), std::string::npos) << n;
    dropped |= n.find("models of 'soft' dropped") != std::string::npos;
  }
  EXPECT_TRUE(dropped);
  // The adopted world is the Moon: the ball falls at the Moon's gravity, no block exists.
  TickOutput out = world.Tick(now + dt, 0.01);
  for (const auto& st : Published(out)) EXPECT_NE(st.object_id().to_string(), "block");
}

}  // namespace
}  // namespace handshare::server

namespace handshare::server {
namespace {

// A body at rest is not streamed, but its pose is published again once per refresh period:
// object states are best-effort, and a receiver that missed the last one (a late joiner whose
// reader matched after the join's re-send) would otherwise draw the body where the scene put it.
int RestingBallPublications(double refresh_period_s) {
  testing::TempDir dir;
  const auto file = WriteBallScene(dir.path(), "rest", -9.81);
  ObjectAuthorityOptions options;
  options.models.cache_dir = dir.path() / "cache";
  options.pose_refresh_period = std::chrono::duration<double>(refresh_period_s);
  ObjectAuthority world("s", options);
  world.SetScene(scene::LoadScene(file));
  const auto dt = std::chrono::milliseconds(10);
  Clock::time_point now = TickUntilReady(world, Clock::now());
  EXPECT_TRUE(world.ready());
  for (int i = 0; i < 200; ++i) {  // 2 s to settle on the ground
    now += dt;
    world.Tick(now, 0.01);
  }
  int published = 0;
  for (int i = 0; i < 350; ++i) {  // 3.5 s at rest
    now += dt;
    if (BallState(world.Tick(now, 0.01)) != nullptr) ++published;
  }
  return published;
}

TEST(ObjectAuthority, ABodyAtRestIsPublishedAgainOncePerRefreshPeriod) {
  const int refreshed = RestingBallPublications(1.0);
  EXPECT_GE(refreshed, 3);  // at 1.0 s, 2.0 s, 3.0 s (+ one at the start of the window)
  EXPECT_LE(refreshed, 4);
  EXPECT_EQ(RestingBallPublications(0.0), 0);  // the negative control: a resting body is not streamed
}

}  // namespace
}  // namespace handshare::server

namespace handshare::server {
namespace {

// A resumed session (a restarted server) places the ball where its log left it, in alice's
// hand. Until her claim arrives the server neither simulates nor publishes it as free (her
// node would follow that free ball: a held weight read 0 to 11.7 N through a restart); her
// claim grants it back. Without a claim it is free after the grace and falls.
void ResumedBall(bool alice_claims) {
  testing::TempDir dir;
  const auto file = WriteBallScene(dir.path(), "moon", -kMoon);
  ObjectAuthorityOptions options;
  options.models.cache_dir = dir.path() / "cache";
  ObjectAuthority world("s", options);
  const Eigen::Vector3d held(0.0, 0.0, 0.15);  // lifted in her hand when the server died
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = held;
  world.PlaceBody("ball", X, "alice", std::chrono::seconds(2));
  world.SetScene(scene::LoadScene(file));
  const auto dt = std::chrono::milliseconds(10);
  Clock::time_point now =
      TickUntilReady(world, Clock::now(), [](const TickOutput& out) { EXPECT_EQ(BallState(out), nullptr); });
  ASSERT_TRUE(world.ready());
  // 1.5 s without her claim (her node rediscovering the new server): not published, not moved.
  for (int i = 0; i < 150; ++i) {
    now += dt;
    const TickOutput out = world.Tick(now, 0.01);
    ASSERT_EQ(BallState(out), nullptr) << "tick " << i << ": the held ball was published before its owner's claim";
  }
  if (alice_claims) {
    now += dt;
    world.OnContactSet(OwnerSet("ball", held, Eigen::Vector3d::Zero()), now);
    const TickOutput out = world.Tick(now, 0.01);
    EXPECT_EQ(world.owner("ball"), "alice");
    const msg::ObjectState* st = BallState(out);
    ASSERT_NE(st, nullptr);
    EXPECT_EQ(st->owner().to_string(), "alice");
    EXPECT_NEAR(st->p_WO_m()[2], held.z(), 1e-9);
    return;
  }
  // No claim: free once the 2 s grace (from the models' adoption) has passed, then it falls.
  bool freed = false;
  double z = held.z();
  for (int i = 0; i < 100; ++i) {
    now += dt;
    const TickOutput out = world.Tick(now, 0.01);
    for (const auto& note : out.notes) freed = freed || note == "object 'ball': no claim from 'alice', free";
    if (const msg::ObjectState* st = BallState(out)) {
      EXPECT_EQ(st->owner().to_string(), "");
      z = st->p_WO_m()[2];
    }
  }
  EXPECT_TRUE(freed);
  EXPECT_LT(z, held.z() - 0.01);  // falling on the Moon
}

TEST(ObjectAuthority, AResumedOwnersBodyWaitsForItsClaimInsteadOfBeingPublishedFree) { ResumedBall(true); }

TEST(ObjectAuthority, AResumedOwnersBodyWithoutAClaimIsFreeAfterTheGrace) { ResumedBall(false); }

}  // namespace
}  // namespace handshare::server
