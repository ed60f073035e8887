#include "handshare/session/peer_contacts.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace handshare::session {
namespace {

using namespace std::chrono_literals;
using Clock = PeerContacts::Clock;

msg::ContactSet Set(const std::string& user, const std::string& object, double u_z, double f_z) {
  msg::ContactSet s;
  s.user(user);
  s.fingers()[1].active(true);
  s.fingers()[1].object_id(object);
  s.fingers()[1].p_OC_m({0.01, 0.02, 0.03});
  s.fingers()[1].u_O_m({0.0, 0.0, u_z});
  s.fingers()[1].n_O({0.0, 0.6, 0.8});
  s.fingers()[1].f_O_N({0.0, 0.0, f_z});
  s.fingers()[3].active(false);
  s.fingers()[3].object_id(object);
  return s;
}

struct Seen {
  std::int32_t object, finger, hand;
  double u_z, f_z, weight;
  Eigen::Vector3d n_W;
};

// The contacts as a solve at `now` takes them: faded by their age (contact::FadedContact).
std::vector<Seen> Collect(const PeerContacts& peers, const world::SceneModels& models, Clock::time_point now) {
  std::vector<Seen> out;
  const std::uint64_t now_ns = PeerContacts::SteadyNs(now);
  peers.ForEach(models, now, [&](const PeerContact& c, const msg::ContactSet&) {
    const contact::FingerContact r = contact::FadedContact(c, peers.fade(), now_ns);
    out.push_back({r.object, r.finger, c.hand, r.u_O_m[2], -r.f_O_N[2], peers.fade().WeightAt(now_ns, c.received_ns),
                   contact::AsVector(r.n_O)});
  });
  return out;
}

class PeerContactsTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { models_ = new world::SceneModels(world::BuildSceneModels(scene::LoadSceneByName("solar_system"))); }
  static void TearDownTestSuite() { delete models_; }
  static world::SceneModels* models_;
};
world::SceneModels* PeerContactsTest::models_ = nullptr;

TEST_F(PeerContactsTest, ActiveFingersOnKnownObjectsOnly) {
  PeerContacts peers;
  const auto t0 = Clock::now();
  peers.Receive(Set("bob", "ball", -0.002, -1.5), t0, "alice");
  peers.Receive(Set("alice", "ball", -0.001, -1.0), t0, "alice");     // our own: ignored
  peers.Receive(Set("carol", "no_such_object", -0.001, -1.0), t0, "alice");
  const auto seen = Collect(peers, *models_, t0);
  ASSERT_EQ(seen.size(), 1u);
  EXPECT_EQ(seen[0].object, models_->Find("ball"));
  EXPECT_EQ(seen[0].finger, 1);
  EXPECT_DOUBLE_EQ(seen[0].u_z, -0.002);
  EXPECT_EQ(seen[0].n_W, Eigen::Vector3d(0.0, 0.6, 0.8));  // the normal crosses the DDS boundary
  EXPECT_DOUBLE_EQ(seen[0].f_z, 1.5);  // the peer's fingertip feels minus the force on the object
  EXPECT_DOUBLE_EQ(seen[0].weight, 1.0);
}

TEST_F(PeerContactsTest, AVanishedPeerFadesOutLinearlyThenGoes) {
  PeerContacts peers({200ms, 500ms});
  const auto t0 = Clock::now();
  peers.Receive(Set("bob", "ball", -0.004, -2.0), t0);
  EXPECT_DOUBLE_EQ(Collect(peers, *models_, t0 + 200ms).at(0).weight, 1.0);
  const auto half = Collect(peers, *models_, t0 + 350ms);
  ASSERT_EQ(half.size(), 1u);
  EXPECT_NEAR(half[0].weight, 0.5, 1e-9);
  EXPECT_NEAR(half[0].u_z, -0.002, 1e-12);
  EXPECT_NEAR(half[0].f_z, 1.0, 1e-9);
  // The largest change between two 10 ms ticks is 10/300 of the contact: no step.
  double prev = 1.0;
  for (auto t = 200ms; t <= 500ms; t += 10ms) {
    const auto now = Collect(peers, *models_, t0 + t);
    const double w = now.empty() ? 0.0 : now[0].weight;
    EXPECT_LE(prev - w, 10.0 / 300.0 + 1e-9) << "at " << t.count() << " ms";
    prev = w;
  }
  EXPECT_TRUE(Collect(peers, *models_, t0 + 500ms).empty());
  peers.Expire(t0 + 499ms);
  EXPECT_EQ(peers.sets().size(), 1u);
  peers.Expire(t0 + 500ms);
  EXPECT_TRUE(peers.sets().empty());
}

TEST_F(PeerContactsTest, ANewerSetReplacesTheOldAndRefreshes) {
  PeerContacts peers;
  const auto t0 = Clock::now();
  peers.Receive(Set("bob", "ball", -0.004, -2.0), t0);
  auto lifted = Set("bob", "ball", 0.0, 0.0);
  lifted.fingers()[1].active(false);
  peers.Receive(lifted, t0 + 300ms);
  EXPECT_TRUE(Collect(peers, *models_, t0 + 300ms).empty());  // lifting ends at once
  EXPECT_EQ(peers.sets().size(), 1u);
}

// The contacts come out as their set carried them, with the set's arrival time: the step that
// uses them fades them at its own time, so a late hand-over cannot hold the fade still.
TEST_F(PeerContactsTest, ContactsComeOutUnfadedWithTheirArrivalTime) {
  PeerContacts peers({200ms, 500ms});
  const auto t0 = Clock::now();
  peers.Receive(Set("bob", "ball", -0.004, -2.0), t0);
  int seen = 0;
  peers.ForEach(*models_, t0 + 350ms, [&](const PeerContact& c, const msg::ContactSet&) {
    ++seen;
    EXPECT_EQ(c.received_ns, PeerContacts::SteadyNs(t0));
    EXPECT_DOUBLE_EQ(c.contact.u_O_m[2], -0.004);
    EXPECT_DOUBLE_EQ(-c.contact.f_O_N[2], 2.0);
  });
  EXPECT_EQ(seen, 1);
  EXPECT_EQ(peers.fade().fade_after_ns, 200'000'000);
  EXPECT_EQ(peers.fade().lifespan_ns, 500'000'000);
  EXPECT_NEAR(peers.fade().rate_per_s(), 1.0 / 0.3, 1e-12);
}

TEST(PeerContactsConfig, RejectsAnEmptyFade) {
  EXPECT_THROW(PeerContacts({500ms, 500ms}), std::invalid_argument);
}

}  // namespace
}  // namespace handshare::session

namespace handshare::session {
namespace {
TEST(FadedContact, CarriesEveryFieldFadedByItsAgeAtTheStep) {
  PeerContact c;
  c.hand = 2;
  c.contact.finger = 4;
  c.contact.object = 7;
  c.received_ns = 1'000'000'000;
  for (int k = 0; k < 3; ++k) {
    c.contact.p_OC_m[k] = 0.1 * (k + 1);
    c.contact.u_O_m[k] = -0.001 * (k + 1);
    c.contact.f_O_N[k] = 1.5 * (k + 1);
    c.contact.n_O[k] = 0.6 * k;
  }
  const contact::PeerFade fade{200'000'000, 500'000'000};
  const contact::FingerContact r = contact::FadedContact(c, fade, c.received_ns + 200'000'000);
  EXPECT_EQ(r.finger, 4);
  EXPECT_EQ(r.object, 7);
  EXPECT_EQ(contact::AsVector(r.p_OC_m), Eigen::Vector3d(0.1, 0.2, 0.30000000000000004));
  EXPECT_EQ(contact::AsVector(r.u_O_m), Eigen::Vector3d(-0.001, -0.002, -0.003));
  EXPECT_EQ(contact::AsVector(r.f_O_N), Eigen::Vector3d(1.5, 3.0, 4.5));
  EXPECT_EQ(contact::AsVector(r.n_O), Eigen::Vector3d(0.0, 0.6, 1.2));
  // Half-way through the fade: u and f halved, the point kept.
  const contact::FingerContact half = contact::FadedContact(c, fade, c.received_ns + 350'000'000);
  EXPECT_EQ(contact::AsVector(half.p_OC_m), contact::AsVector(r.p_OC_m));
  EXPECT_TRUE(contact::AsVector(half.u_O_m).isApprox(0.5 * contact::AsVector(r.u_O_m), 1e-12));
  EXPECT_TRUE(contact::AsVector(half.f_O_N).isApprox(0.5 * contact::AsVector(r.f_O_N), 1e-12));
  EXPECT_EQ(contact::AsVector(half.n_O), contact::AsVector(r.n_O));  // a direction: not faded
  // A step stamped before the set arrived (the hand-over raced the step's clock read): fresh.
  EXPECT_EQ(fade.WeightAt(c.received_ns - 1000, c.received_ns), 1.0);
  EXPECT_EQ(fade.WeightAt(c.received_ns + 500'000'000, c.received_ns), 0.0);
}
}  // namespace
}  // namespace handshare::session
