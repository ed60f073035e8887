// The network coupling's passivity observer and controller (coupling_passivity.hpp): the
// observer against hand-computed energies, the controller on a body that has stiffened since the
// peer's sample, the world's per-contact forces it reads, and no heap in the step. Two delayed
// hands coupled through one body: haptic_node/test/coupling_stability_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "handshare/contact/coupling_passivity.hpp"
#include "handshare/contact/haptic_world.hpp"
#include "handshare/testing/allocation_counter.hpp"
#include "test_util.hpp"

namespace handshare::contact {
namespace {

// A press along -z (the body's outward normal +z) of depth x: the imposed displacement, and the
// force F on the body (along -z) as a fingertip feels it (+z).
PeerContact Sample(double x_m, double F_N, std::uint64_t received_ns) {
  PeerContact c;
  c.hand = 1;
  c.contact.finger = 0;
  c.contact.object = 0;
  c.contact.p_OC_m[2] = 0.0;
  c.contact.u_O_m[2] = -x_m;
  c.contact.n_O[2] = 1.0;
  c.contact.f_O_N[2] = -F_N;  // on the body
  c.received_ns = received_ns;
  return c;
}

Eigen::Vector3d OnBody(double F_N) { return {0.0, 0.0, -F_N}; }

TEST(CouplingPassivity, ObserverIsExactOnALinearSpringWithoutDelay) {
  // The peer presses a 400 N/m spring 0 -> 3 mm in 30 samples; the local body is the same spring,
  // so what the channel hands over is what the peer put in: (1/2) k x^2 at both ends, the
  // observer stays at 0 and the controller never acts.
  const double k = 400.0;
  CouplingPassivity pc;
  double x_prev = 0.0;
  for (int s = 1; s <= 30; ++s) {
    const double x = 1e-4 * s;
    const PeerContact sent = Sample(x, k * x, static_cast<std::uint64_t>(s));
    for (int step = 0; step < 10; ++step) {  // ten haptic steps per sample (zero-order hold)
      pc.BeginStep(1e-3);
      FingerContact in = FadedContact(sent, PeerFade{}, sent.received_ns);
      pc.Admit(sent, in);
      EXPECT_DOUBLE_EQ(in.u_O_m[2], -x);  // passed as sent
      const double imposed = -in.u_O_m[2];
      const std::array<Eigen::Vector3d, 1> F = {OnBody(k * imposed)};
      pc.Observe(F);
    }
    x_prev = x;
  }
  const double e = 0.5 * k * x_prev * x_prev;
  EXPECT_NEAR(pc.stats().energy_sent_J, e, 1e-15);
  EXPECT_NEAR(pc.stats().energy_received_J, e, 1e-15);
  EXPECT_NEAR(pc.observer_J(0, 0, 0), 0.0, 1e-15);
  EXPECT_EQ(pc.stats().held_back, 0u);
  EXPECT_EQ(pc.stats().steps, 300u);
}

// The peer pressed a 400 N/m body; by the time its samples arrive the local body is twice as
// stiff there (the local hand pressed nearby meanwhile). Returns the controller's stats and the
// last imposed depth.
struct StiffenedRun {
  CouplingPassivityStats stats;
  double imposed_m = 0.0;
  double observer_J = 0.0;
};
StiffenedRun PressAStiffenedBody(bool passivity) {
  const double k_peer = 400.0, k_here = 800.0;
  CouplingPassivity pc(passivity);
  StiffenedRun run;
  for (int s = 1; s <= 30; ++s) {
    const double x = 1e-4 * s;
    const PeerContact sent = Sample(x, k_peer * x, static_cast<std::uint64_t>(s));
    for (int step = 0; step < 10; ++step) {
      pc.BeginStep(1e-3);
      FingerContact in = FadedContact(sent, PeerFade{}, sent.received_ns);
      pc.Admit(sent, in);
      run.imposed_m = -in.u_O_m[2];
      const std::array<Eigen::Vector3d, 1> F = {OnBody(k_here * run.imposed_m)};
      pc.Observe(F);
    }
  }
  run.stats = pc.stats();
  run.observer_J = pc.observer_J(0, 0, 0);
  return run;
}

TEST(CouplingPassivity, HoldsBackWhatAStiffenedBodyWouldTakeFromALateDisplacement) {
  // Sent: (1/2) 400 (3 mm)^2 = 1.8 mJ. Passed as sent, the local body would get
  // (1/2) 800 (3 mm)^2 = 3.6 mJ: the channel made 1.8 mJ.
  const StiffenedRun off = PressAStiffenedBody(false);
  EXPECT_NEAR(off.stats.energy_sent_J, 1.8e-3, 1e-12);
  EXPECT_NEAR(off.stats.energy_received_J, 3.6e-3, 1e-12);
  EXPECT_NEAR(off.observer_J, -1.8e-3, 1e-12);
  EXPECT_NEAR(off.imposed_m, 3e-3, 1e-15);
  // With the controller the local body gets no more than was sent (to the first step's
  // prediction error: the stiffness is learnt from the first change), and the depth it holds is
  // the one that stores that energy: sqrt(2 E / k_here) = 2.12 mm.
  const StiffenedRun on = PressAStiffenedBody(true);
  EXPECT_NEAR(on.stats.energy_sent_J, 1.8e-3, 1e-12);
  EXPECT_LE(on.stats.energy_received_J, on.stats.energy_sent_J + 2e-6);
  EXPECT_GE(on.stats.observer_min_J, -2e-6 - 1e-12);  // the first sample: (1/2)(800 - 400)(0.1 mm)^2
  EXPECT_GT(on.stats.held_back, 0u);
  EXPECT_NEAR(on.imposed_m, std::sqrt(2.0 * 1.8e-3 / 800.0), 2e-5);
  EXPECT_NEAR(on.stats.drift_max_m, 3e-3 - on.imposed_m, 1e-5);
}

// The stiffened body of the test above on a real clock: the peer's samples 10 ms apart, 1 ms
// haptic steps. The peer presses 0 -> 3 mm in 30 samples, then (from `then_ms` on) its samples
// follow `after(t_s)` [m] (its force k_peer_after times that) until `end_ms`; a still peer's set
// comes every 100 ms (the deadband's keepalive). Records the imposed depth after every step.
struct ClockedRun {
  CouplingPassivityStats stats;
  std::vector<double> imposed_m;  // one per 1 ms step
  double observer_J = 0.0;
};
template <typename After>
ClockedRun PressOnAClock(After after, int end_ms, int sample_every_ms, double k_peer_after = 400.0) {
  const double k_peer = 400.0, k_here = 800.0;
  CouplingPassivity pc;
  ClockedRun run;
  PeerContact sent;
  for (int ms = 0; ms < end_ms; ++ms) {
    const std::uint64_t now_ns = 1'000'000'000ull + 1'000'000ull * static_cast<std::uint64_t>(ms);
    if (ms < 300 && ms % 10 == 0) {
      const double x = 1e-4 * (ms / 10 + 1);
      sent = Sample(x, k_peer * x, now_ns);
    } else if (ms >= 300 && (ms - 300) % sample_every_ms == 0) {
      const double x = after(1e-3 * (ms - 300));
      sent = Sample(x, k_peer_after * x, now_ns);
    }
    pc.BeginStep(1e-3);
    FingerContact in = FadedContact(sent, PeerFade{}, now_ns);
    pc.Admit(sent, in);
    run.imposed_m.push_back(-in.u_O_m[2]);
    const std::array<Eigen::Vector3d, 1> F = {OnBody(k_here * run.imposed_m.back())};
    pc.Observe(F);
  }
  run.stats = pc.stats();
  run.observer_J = pc.observer_J(0, 0, 0);
  return run;
}

TEST(CouplingPassivity, AStillPeersLagClosesAtTheFadesRateAndTheGrantIsReported) {
  // The peer stops at 3 mm; the controller had held the stiffened local body at 2.12 mm. Once the
  // peer's samples have stayed put for most of a keepalive (two sets, 100 ms apart), the lag
  // closes at the fade's rate (3 mm / 0.3 s = 10 um per 1 ms step), beyond the budget: both
  // copies come to one shape. What that put in beyond what the peer sent is reported:
  // (1/2) 800 (3^2 - 2.12^2) mm^2 = 1.8 mJ (the body is twice as stiff here).
  const ClockedRun run = PressOnAClock([](double) { return 3e-3; }, 1000, 100);
  const double fade_step = PeerFade{}.rate_per_s() * 3e-3 * 1e-3;
  EXPECT_NEAR(run.imposed_m[299], std::sqrt(2.0 * 1.8e-3 / 800.0), 2e-5);  // held back while pressing
  EXPECT_NEAR(run.imposed_m[399], run.imposed_m[299], 1e-9);             // the peer not yet still
  double steepest = 0.0;
  for (std::size_t i = 300; i < run.imposed_m.size(); ++i) {
    steepest = std::max(steepest, run.imposed_m[i] - run.imposed_m[i - 1]);
  }
  EXPECT_LE(steepest, fade_step * (1.0 + 1e-9));
  EXPECT_NEAR(run.imposed_m.back(), 3e-3, 1e-9);  // one shape
  // The lag (0.88 mm) closed in about 88 steps after the second still set.
  const auto caught = std::find_if(run.imposed_m.begin() + 300, run.imposed_m.end(),
                                   [](double x) { return x >= 3e-3 - 1e-9; });
  EXPECT_LE(caught - run.imposed_m.begin(), 400 + 92);
  EXPECT_NEAR(run.stats.energy_granted_J, 0.5 * 800.0 * (9e-6 - 2.0 * 1.8e-3 / 800.0), 2e-5);
  EXPECT_GT(run.stats.granted_still, 80u);
  EXPECT_GE(run.stats.observer_min_J, -2e-6 - 1e-12);  // the grant counts as sent
  EXPECT_NEAR(run.observer_J, 0.0, 2e-6);
}

TEST(CouplingPassivity, AnOscillatingPeerNeverGetsAGrant) {
  // The same press, then the peer swings +-0.5 mm about 2.5 mm at 2 Hz for 3 s, a set every
  // 10 ms: it never stops, so the controller holds the stiffened body within what was sent.
  const ClockedRun run = PressOnAClock(
      [](double t) { return 2.5e-3 + 0.5e-3 * std::sin(2.0 * M_PI * 2.0 * t); }, 3300, 10);
  EXPECT_EQ(run.stats.granted_still, 0u);
  EXPECT_EQ(run.stats.energy_granted_J, 0.0);
  EXPECT_GT(run.stats.held_back, 0u);
  EXPECT_GE(run.stats.observer_min_J, -2e-6 - 1e-12);
  EXPECT_LE(run.stats.energy_received_J, run.stats.energy_sent_J + 2e-6);
}

TEST(CouplingPassivity, AfterAHoldTheLagClosesAtTheFadesRateNotAFingertipsSpeed) {
  // Held at 2.12 mm by the stiffened body, the peer then jumps to 6 mm against a body that is
  // stiff at its end (4,000 N/m): a set that brings far more energy than the local body needs.
  // The sample's own jump passes at a fingertip's speed (0.25 mm per step, as from an unheld
  // channel), the 0.88 mm lag from before at the fade's rate (at most 6 mm / 0.3 s = 20 um per
  // step), not in a few steps at a fingertip's speed.
  const ClockedRun run = PressOnAClock([](double) { return 6e-3; }, 330, 100, 4000.0);
  const double jump_step = CouplingPassivity::kMaxSpeed_m_per_s * 1e-3;
  const double fade_step = PeerFade{}.rate_per_s() * 6e-3 * 1e-3;
  for (std::size_t i = 300; i < run.imposed_m.size(); ++i) {
    EXPECT_LE(run.imposed_m[i] - run.imposed_m[i - 1], jump_step + 1e-12) << i;
  }
  // After the jump's 3 mm passed (12 steps), what is left of the lag closes at <= the fade's rate.
  for (std::size_t i = 313; i < run.imposed_m.size(); ++i) {
    EXPECT_LE(run.imposed_m[i] - run.imposed_m[i - 1], fade_step * (1.0 + 1e-9)) << i;
  }
  EXPECT_LT(run.imposed_m.back(), 6e-3 - 1e-4);  // still closing, 30 ms later
  EXPECT_EQ(run.stats.granted_still, 0u);
}

TEST(CouplingPassivity, AUsersChannelOutlivesAChangeOfItsHandIndex) {
  // Hands are numbered in user-name order, so bob's contacts become hand 2 when aaron joins. His
  // channel is his (the user's key): his held press goes on as it was. Keyed by hand index, his
  // 3 mm press opened a new channel at 0 and came back at the rate limit: the other hand's body
  // let go of his patch for 12 ms.
  CouplingPassivity pc;
  const std::uint64_t bob = UserKey("bob"), aaron = UserKey("aaron");
  ASSERT_NE(bob, aaron);
  double imposed_m = 0.0;
  auto step = [&](const PeerContact& sent, std::uint64_t now_ns) {
    pc.BeginStep(1e-3);
    FingerContact in = FadedContact(sent, PeerFade{}, now_ns);
    pc.Admit(sent, in);
    imposed_m = -in.u_O_m[2];
    const std::array<Eigen::Vector3d, 1> F = {OnBody(400.0 * imposed_m)};
    pc.Observe(F);
  };
  for (int ms = 0; ms < 300; ++ms) {  // bob presses 0 -> 3 mm, then holds, as hand 1
    const double x = std::min(3e-3, 1e-4 * (ms / 10 + 1));
    PeerContact c = Sample(x, 400.0 * x, 1'000'000ull * static_cast<std::uint64_t>(ms - ms % 10 + 1));
    c.user_key = bob;
    step(c, 1'000'000ull * static_cast<std::uint64_t>(ms + 1));
  }
  ASSERT_NEAR(imposed_m, 3e-3, 1e-12);
  PeerContact c = Sample(3e-3, 1.2, 301'000'000ull);
  c.user_key = bob;
  c.hand = 2;  // aaron joined
  step(c, 301'000'000ull);
  EXPECT_NEAR(imposed_m, 3e-3, 1e-12);
  EXPECT_EQ(pc.stats().channels_total, 1u);
  // And aaron, now hand 1 on the same finger and object, gets a channel of his own.
  PeerContact a = Sample(1e-3, 0.4, 302'000'000ull);
  a.user_key = aaron;
  step(a, 302'000'000ull);
  EXPECT_EQ(pc.stats().channels_total, 2u);
}

TEST(CouplingPassivity, TheWorldReportsEachRemoteContactsForceOnTheBody) {
  // One remote fingertip alone on a block: its patch force is everything the solve holds.
  HapticWorld w;
  const test::SoftBlock b = test::MakeSoftBlock();
  DeformableDesc d;
  d.mesh = b.mesh;
  d.compliance = b.C;
  d.X_WO = Eigen::Translation3d(0.6, 0, 0) * Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ());
  const ObjectId block = w.AddDeformable(d);
  w.Init();
  std::array<FingerContact, 2> remote = {
      ContactInObjectFrame(d.X_WO, 0, block, d.X_WO * Eigen::Vector3d(0.03, 0.03, 0.03),
                           d.X_WO * Eigen::Vector3d(0.03, 0.03, 0.037), Eigen::Vector3d(0, 0, -0.001),
                           Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d(0, 0, 1)),
      ContactInObjectFrame(d.X_WO, 1, block, Eigen::Vector3d::Constant(NAN), Eigen::Vector3d::Constant(NAN),
                           Eigen::Vector3d(0, 0, -0.001))};
  std::array<Eigen::Vector3d, kFingers> far;
  far.fill(Eigen::Vector3d(0, 0, 1));
  w.Step(1e-3, far, remote);
  ASSERT_EQ(w.remote_forces_O().size(), 2u);
  const auto remote_forces_W = [&](std::size_t r) { return Eigen::Vector3d(d.X_WO.linear() * w.remote_forces_O()[r]); };
  Eigen::Vector3d held = Eigen::Vector3d::Zero();
  for (const auto& l : w.held_loads(block)) held += l.f_N;
  held = d.X_WO.linear() * held;
  EXPECT_GT(held.norm(), 0.01);
  EXPECT_LT((remote_forces_W(0) - held).norm(), 1e-12 * held.norm());
  EXPECT_LT(remote_forces_W(0).z(), 0.0);  // pushed in
  EXPECT_EQ(remote_forces_W(1), Eigen::Vector3d::Zero());  // rejected: not in the solve
}

// The weights a haptic step gives the peers' contacts (PeerWeights): the fade law's going down
// and for a new contact; going up again (a newer set after a stalled bridge, or a contact back
// within kMemory_ns after it had gone) at the fade's rate; a contact unseen for longer than
// kMemory_ns starts at the law's weight again.
TEST(PeerWeights, AContactComingBackRisesAtTheFadesRate) {
  PeerWeights weights;
  PeerContact c;
  c.user_key = UserKey("bob");
  c.contact.finger = 1;
  c.contact.object = 3;
  const double rate = 1.0 / 0.3, dt = 1e-3;
  std::uint64_t now = 1'000'000'000;
  auto step = [&](double law) {
    now += 1'000'000;
    const double w = weights.Weight(c, law, dt, rate, now);
    weights.EndStep(now);
    return w;
  };
  EXPECT_EQ(step(1.0), 1.0);   // new: the law's weight
  EXPECT_EQ(step(0.4), 0.4);   // fading: the law's
  EXPECT_NEAR(step(1.0), 0.4 + rate * dt, 1e-12);  // a fresh set: back at the fade's rate
  double w = 0.0;
  for (int k = 0; k < 300; ++k) w = step(1.0);
  EXPECT_EQ(w, 1.0);
  // Gone for a step (faded out, or the finger left the set), then back: from 0.
  now += 1'000'000;
  weights.EndStep(now);
  EXPECT_NEAR(step(1.0), rate * dt, 1e-12);
  // Another finger of the same user is another contact: new, at the law's weight.
  c.contact.finger = 2;
  EXPECT_EQ(step(0.7), 0.7);
  // Unseen for longer than the memory: new again.
  now += PeerWeights::kMemory_ns + 1'000'000;
  weights.EndStep(now);
  c.contact.finger = 1;
  EXPECT_EQ(step(1.0), 1.0);
}

TEST(CouplingPassivity, AdmitAndObserveDoNotAllocate) {
  CouplingPassivity pc;
  const std::array<Eigen::Vector3d, 2> F = {OnBody(0.5), OnBody(0.2)};
  const long before = testing::AllocationCount();
  for (int s = 0; s < 100; ++s) {
    pc.BeginStep(1e-3);
    for (int f = 0; f < 2; ++f) {
      PeerContact sent = Sample(1e-4 * (s % 7), 0.1 * (s % 5), static_cast<std::uint64_t>(s / 3));
      sent.contact.finger = f;
      FingerContact in = FadedContact(sent, PeerFade{}, sent.received_ns);
      pc.Admit(sent, in);
    }
    pc.Observe(F);
  }
  EXPECT_EQ(testing::AllocationCount() - before, 0);
}

}  // namespace
}  // namespace handshare::contact
