// The peer-fade stage (PeerFadeStage): the one loop the haptic renderer and the world server
// both run over the peers' contacts before a solve.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>

#include "handshare/contact/peer_contact.hpp"
#include "handshare/testing/allocation_counter.hpp"

namespace handshare::contact {
namespace {

constexpr std::uint64_t kMs = 1'000'000;

PeerContact Received(const char* user, std::int32_t finger, std::uint64_t received_ns) {
  PeerContact c;
  c.user_key = UserKey(user);
  c.received_ns = received_ns;
  c.contact.finger = finger;
  c.contact.object = 2;
  c.contact.u_O_m = {0.0, 0.0, -0.002};
  c.contact.f_O_N = {0.0, 0.0, -1.0};
  c.contact.p_OC_m = {0.01, 0.02, 0.03};
  return c;
}

// Fresh contacts pass whole, fading ones at the law's weight, dead ones leave the solve; the
// rest keep their order and say where they came from.
TEST(PeerFadeStage, WeighsEachContactByItsAgeAtTheStepAndDropsTheDead) {
  const PeerFade fade;  // full until 300 ms, zero at 600 ms
  const std::uint64_t now = 10'000 * kMs;
  const std::array<PeerContact, 4> peers = {
      Received("ann", 0, now - 100 * kMs),   // fresh: 1
      Received("bob", 1, now - 700 * kMs),   // past its lifespan: 0, leaves
      Received("cat", 2, now - 450 * kMs),   // half way through the fade: 0.5
      Received("dan", 3, now + 5 * kMs)};    // stamped after the step (another thread's clock): 1
  PeerFadeStage stage;
  std::array<FingerContact, 8> out{};
  std::array<std::int32_t, 8> from{};
  from.fill(-1);
  ASSERT_EQ(stage.Step(peers, fade, 1e-3, now, out, from), 3u);
  EXPECT_EQ(from[0], 0);
  EXPECT_EQ(from[1], 2);
  EXPECT_EQ(from[2], 3);
  EXPECT_EQ(from[3], -1);
  EXPECT_EQ(out[0].finger, 0);
  EXPECT_EQ(out[0].u_O_m[2], -0.002);
  EXPECT_EQ(out[0].f_O_N[2], -1.0);
  EXPECT_EQ(out[1].finger, 2);
  EXPECT_NEAR(out[1].u_O_m[2], -0.001, 1e-15);
  EXPECT_NEAR(out[1].f_O_N[2], -0.5, 1e-12);
  EXPECT_EQ(out[1].p_OC_m[0], 0.01);  // where it touches is not faded
  EXPECT_EQ(out[2].finger, 3);
  EXPECT_EQ(out[2].u_O_m[2], -0.002);
}

// A contact whose set aged into the fade and then came back fresh (its sender's bridge
// stalled) rises at the fade's rate, step by step, as it went down: the stage keeps each
// contact's weight from one step to the next.
TEST(PeerFadeStage, AContactComingBackRisesAtTheFadesRate) {
  const PeerFade fade;
  const double rate = fade.rate_per_s(), dt = 1e-3;
  PeerFadeStage stage;
  std::array<FingerContact, 1> out{};
  std::uint64_t now = 10'000 * kMs;
  PeerContact c = Received("ann", 1, now - 450 * kMs);  // at 0.5
  ASSERT_EQ(stage.Step({&c, 1}, fade, dt, now, out), 1u);
  EXPECT_NEAR(out[0].f_O_N[2], -0.5, 1e-12);
  c.received_ns = now;  // a fresh set: the law says 1
  for (int k = 1; k <= 3; ++k) {
    now += kMs;
    ASSERT_EQ(stage.Step({&c, 1}, fade, dt, now, out), 1u);
    EXPECT_NEAR(out[0].f_O_N[2], -(0.5 + k * rate * dt), 1e-9) << "step " << k;
  }
}

// Once the solve's room is full the rest are not weighed: a contact left out comes in later
// as a new one, at its law's weight, not from a weight it never had.
TEST(PeerFadeStage, ContactsBeyondTheRoomAreNotWeighed) {
  const PeerFade fade;
  PeerFadeStage stage;
  std::uint64_t now = 10'000 * kMs;
  std::array<PeerContact, 2> peers = {Received("ann", 0, now), Received("bob", 0, now - 450 * kMs)};
  std::array<FingerContact, 1> one{};
  ASSERT_EQ(stage.Step(peers, fade, 1e-3, now, one), 1u);
  EXPECT_EQ(one[0].finger, 0);
  EXPECT_EQ(one[0].f_O_N[2], -1.0);
  // bob's set is fresh now: had it been weighed at 0.5 above it would rise from there.
  now += kMs;
  peers[1].received_ns = now;
  std::array<FingerContact, 2> two{};
  ASSERT_EQ(stage.Step(peers, fade, 1e-3, now, two), 2u);
  EXPECT_EQ(two[1].f_O_N[2], -1.0);
}

TEST(PeerFadeStage, DoesNotAllocate) {
  const PeerFade fade;
  PeerFadeStage stage;
  std::array<PeerContact, 40> peers{};
  std::array<FingerContact, 40> out{};
  std::array<std::int32_t, 40> from{};
  std::uint64_t now = 10'000 * kMs;
  const long before = testing::AllocationCount();
  for (int s = 0; s < 200; ++s) {
    now += kMs;
    for (int i = 0; i < 40; ++i) {
      peers[static_cast<std::size_t>(i)] = Received(i % 2 ? "ann" : "bob", i % 5, now - static_cast<std::uint64_t>((s * 7 + i) % 700) * kMs);
      peers[static_cast<std::size_t>(i)].contact.object = i / 10;
    }
    stage.Step(peers, fade, 1e-3, now, out, from);
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
}

}  // namespace
}  // namespace handshare::contact
