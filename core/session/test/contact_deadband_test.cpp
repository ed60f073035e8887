#include "handshare/session/contact_deadband.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace handshare::session {
namespace {

constexpr std::uint64_t kMs = 1'000'000;

// A hand pressing a deformable with its index finger: force f_z, imposed displacement u_z.
msg::ContactSet Press(double f_z, double u_z) {
  msg::ContactSet s;
  s.user("bob");
  auto& f = s.fingers()[1];
  f.active(true);
  f.object_id("tail");
  f.surface_node(42);
  f.radius_m(0.008);
  f.p_OC_m({0.10, 0.20, 0.30});
  f.p_OE_m({0.10, 0.20, 0.30 + 0.008 - 0.001});
  f.n_O({0.0, 0.0, 1.0});
  f.depth_m(0.001);
  f.u_O_m({0.0, 0.0, u_z});
  f.f_O_N({0.0, 0.0, f_z});
  return s;
}

// A hand that grasps and simulates the ball, carrying it up at 0.1 m/s, 10 cm above the origin.
msg::ContactSet Carried() {
  msg::ContactSet s;
  s.grasped_object_id("ball");
  s.simulating(true);
  s.simulated_object_id("ball");
  s.p_WO_m({0.0, 0.0, 0.1});
  s.q_WO_wxyz({1.0, 0.0, 0.0, 0.0});
  s.v_WO_m_per_s({0.0, 0.0, 0.1});
  return s;
}

TEST(PerceptibleChange, ForceFollowsWebersLawAboveTheFloor) {
  const DeadbandConfig c;  // 10 %, floor 0.02 N
  const msg::ContactSet sent = Press(-2.0, -0.001);
  EXPECT_EQ(PerceptibleChange(sent, Press(-2.19, -0.001), 0.0, c), DeadbandReason::kNone);   // 9.5 %
  EXPECT_EQ(PerceptibleChange(sent, Press(-2.21, -0.001), 0.0, c), DeadbandReason::kForce);  // 10.5 %
  EXPECT_EQ(PerceptibleChange(sent, Press(-1.79, -0.001), 0.0, c), DeadbandReason::kForce);
  // Near zero force the floor rules: 0.015 N from 0.05 N is 30 % but not felt.
  EXPECT_EQ(PerceptibleChange(Press(-0.05, -0.001), Press(-0.065, -0.001), 0.0, c), DeadbandReason::kNone);
  EXPECT_EQ(PerceptibleChange(Press(-0.05, -0.001), Press(-0.075, -0.001), 0.0, c), DeadbandReason::kForce);
  // The same change with a 20 % fraction stays home.
  DeadbandConfig wide = c;
  wide.weber = 0.20;
  EXPECT_EQ(PerceptibleChange(sent, Press(-2.3, -0.001), 0.0, wide), DeadbandReason::kNone);
}

TEST(PerceptibleChange, ForceIsAVectorNotItsNorm) {
  // A 2 N force turning by 10 degrees keeps its norm but moves by 0.35 N: it counts.
  const DeadbandConfig c;
  msg::ContactSet turned = Press(-2.0, -0.001);
  const double a = 10.0 * M_PI / 180.0;
  turned.fingers()[1].f_O_N({2.0 * std::sin(a), 0.0, -2.0 * std::cos(a)});
  EXPECT_EQ(PerceptibleChange(Press(-2.0, -0.001), turned, 0.0, c), DeadbandReason::kForce);
}

TEST(PerceptibleChange, ImposedDisplacement) {
  const DeadbandConfig c;  // 10 %, floor 10 um
  EXPECT_EQ(PerceptibleChange(Press(-2.0, -0.001), Press(-2.0, -0.00109), 0.0, c), DeadbandReason::kNone);
  EXPECT_EQ(PerceptibleChange(Press(-2.0, -0.001), Press(-2.0, -0.00111), 0.0, c), DeadbandReason::kDisplacement);
  EXPECT_EQ(PerceptibleChange(Press(-2.0, -0.00001), Press(-2.0, -0.000019), 0.0, c), DeadbandReason::kNone);  // floor
}

TEST(PerceptibleChange, TheContactPointUsesAnAbsoluteThreshold) {
  const DeadbandConfig c;  // 0.5 mm
  msg::ContactSet moved = Press(-2.0, -0.001);
  moved.fingers()[1].p_OC_m()[0] += 0.0004;
  EXPECT_EQ(PerceptibleChange(Press(-2.0, -0.001), moved, 0.0, c), DeadbandReason::kNone);
  moved.fingers()[1].p_OC_m()[0] += 0.0002;
  EXPECT_EQ(PerceptibleChange(Press(-2.0, -0.001), moved, 0.0, c), DeadbandReason::kPosition);
}

// What no receiver reads does not make a set go out: the fingertip centre, the normal and the
// depth ride along with the sets that do.
TEST(PerceptibleChange, FieldsNoReceiverReadsRideAlong) {
  const DeadbandConfig c;
  msg::ContactSet other = Press(-2.0, -0.001);
  other.fingers()[1].p_OE_m()[0] += 0.003;
  other.fingers()[1].n_O({std::sin(0.2), 0.0, std::cos(0.2)});
  other.fingers()[1].depth_m(0.002);
  EXPECT_EQ(PerceptibleChange(Press(-2.0, -0.001), other, 0.0, c), DeadbandReason::kNone);
}

// A finger on a rigid body or a control (surface node -1): only touching or lifting counts.
TEST(PerceptibleChange, OnARigidBodyOnlyTheTouchCounts) {
  const DeadbandConfig c;
  msg::ContactSet a = Press(-2.0, 0.0), b = Press(-4.0, 0.0);
  a.fingers()[1].surface_node(-1);
  b.fingers()[1].surface_node(-1);
  b.fingers()[1].p_OC_m()[0] += 0.01;
  EXPECT_EQ(PerceptibleChange(a, b, 0.0, c), DeadbandReason::kNone);
  b.fingers()[1].object_id("button");
  EXPECT_EQ(PerceptibleChange(a, b, 0.0, c), DeadbandReason::kStructure);
}

TEST(PerceptibleChange, WhatTheReceiverSolvesAlwaysGoesOut) {
  const DeadbandConfig c;
  const msg::ContactSet sent = Press(-2.0, -0.001);
  msg::ContactSet lifted = sent;
  lifted.fingers()[1].active(false);
  EXPECT_EQ(PerceptibleChange(sent, lifted, 0.0, c), DeadbandReason::kStructure);
  msg::ContactSet second = sent;
  second.fingers()[0] = sent.fingers()[1];
  EXPECT_EQ(PerceptibleChange(sent, second, 0.0, c), DeadbandReason::kStructure);
  msg::ContactSet slid = sent;
  slid.fingers()[1].surface_node(43);
  EXPECT_EQ(PerceptibleChange(sent, slid, 0.0, c), DeadbandReason::kStructure);
  msg::ContactSet other = sent;
  other.fingers()[1].object_id("head");
  EXPECT_EQ(PerceptibleChange(sent, other, 0.0, c), DeadbandReason::kStructure);
  msg::ContactSet grasp = sent;
  grasp.grasped_object_id("ball");
  EXPECT_EQ(PerceptibleChange(sent, grasp, 0.0, c), DeadbandReason::kStructure);
  msg::ContactSet owns = grasp;
  owns.simulating(true);
  owns.simulated_object_id("ball");
  EXPECT_EQ(PerceptibleChange(grasp, owns, 0.0, c), DeadbandReason::kStructure);
  // A finger that is off and stays off: its stale fields are not read.
  msg::ContactSet off_a = sent, off_b = sent;
  off_a.fingers()[3].f_O_N({0.0, 0.0, 5.0});
  off_b.fingers()[3].f_O_N({0.0, 0.0, -5.0});
  EXPECT_EQ(PerceptibleChange(off_a, off_b, 0.0, c), DeadbandReason::kNone);
}

TEST(PerceptibleChange, AHeldBodysPoseAndVelocity) {
  const DeadbandConfig c;
  const msg::ContactSet held = Carried();
  msg::ContactSet next = held;
  next.p_WO_m()[2] += 0.0004;
  EXPECT_EQ(PerceptibleChange(held, next, 0.0, c), DeadbandReason::kNone);
  next.p_WO_m()[2] += 0.0002;
  EXPECT_EQ(PerceptibleChange(held, next, 0.0, c), DeadbandReason::kBody);
  msg::ContactSet turned = held;
  turned.q_WO_wxyz({std::cos(0.01), std::sin(0.01), 0.0, 0.0});  // 0.02 rad
  EXPECT_EQ(PerceptibleChange(held, turned, 0.0, c), DeadbandReason::kBody);
  msg::ContactSet flipped = held;
  flipped.q_WO_wxyz({-1.0, 0.0, 0.0, 0.0});  // the same orientation
  EXPECT_EQ(PerceptibleChange(held, flipped, 0.0, c), DeadbandReason::kNone);
  // A new velocity counts through the reckoning only: at once it changes nothing the receiver
  // shows; 50 ms on, the body carried at 0.12 m/s is 1 mm past the receiver's 0.1 m/s reckoning.
  msg::ContactSet faster = held;
  faster.v_WO_m_per_s()[2] = 0.12;
  EXPECT_EQ(PerceptibleChange(held, faster, 0.0, c), DeadbandReason::kNone);
  faster.p_WO_m()[2] += 0.12 * 0.05;
  EXPECT_EQ(PerceptibleChange(held, faster, 0.05, c), DeadbandReason::kBody);
}

// A body carried at a steady 0.1 m/s: receivers reckon it forward, so 50 ms later it is where
// they put it (5 mm on) and nothing goes out; had it stopped, it is 5 mm behind: a set goes out.
TEST(PerceptibleChange, AHeldBodyAgainstTheReceiversReckoning) {
  const DeadbandConfig c;
  const msg::ContactSet held = Carried();
  msg::ContactSet on = held;
  on.p_WO_m()[2] = 0.105;
  EXPECT_EQ(PerceptibleChange(held, on, 0.05, c), DeadbandReason::kNone);
  msg::ContactSet stopped = held;
  stopped.v_WO_m_per_s()[2] = 0.0;
  EXPECT_EQ(PerceptibleChange(held, stopped, 0.05, c), DeadbandReason::kBody);
  // The reckoning stops after kMaxReckoning_s.
  EXPECT_NEAR(ReckonedPosition(held, 1.0)[2], 0.1 + 0.1 * kMaxReckoning_s, 1e-15);
  EXPECT_NEAR(ReckonedPosition(held, -1.0)[2], 0.1, 1e-15);
}

TEST(ContactSetDeadband, SendsTheFirstThenOnlyPerceptibleChangesAndKeepalives) {
  ContactSetDeadband deadband;  // 10 %, keepalive 100 ms
  DeadbandReason why{};
  EXPECT_TRUE(deadband.Offer(Press(-2.0, -0.001), 0, &why));
  EXPECT_EQ(why, DeadbandReason::kFirst);
  // A slow drift: each step is small, but the reference is the last set sent, so the drift
  // goes out once it adds up to 10 %.
  double f = -2.0;
  int sent_at = -1;
  for (int tick = 1; tick <= 9; ++tick) {
    f -= 0.03;
    if (deadband.Offer(Press(f, -0.001), tick * 10 * kMs, &why)) {
      sent_at = tick;
      EXPECT_EQ(why, DeadbandReason::kForce);
      break;
    }
  }
  EXPECT_EQ(sent_at, 7);  // 7 x 0.03 = 0.21 N > 0.2 N
  // A still hand: only keepalives, every 100 ms.
  const std::uint64_t t0 = 70 * kMs;
  int keepalives = 0;
  for (int tick = 1; tick <= 100; ++tick) {
    if (deadband.Offer(Press(f, -0.001), t0 + tick * 10 * kMs, &why)) {
      EXPECT_EQ(why, DeadbandReason::kKeepalive);
      EXPECT_EQ(tick % 10, 0) << "a keepalive at tick " << tick;
      ++keepalives;
    }
  }
  EXPECT_EQ(keepalives, 10);
  EXPECT_EQ(deadband.offered(), 108u);
  EXPECT_EQ(deadband.sent(), 12u);
  EXPECT_EQ(deadband.sent_for(DeadbandReason::kKeepalive), 10u);
  EXPECT_NEAR(deadband.reduction(), 1.0 - 12.0 / 108.0, 1e-12);
  // Reset (a new scene): the next set goes out at once.
  deadband.Reset();
  EXPECT_TRUE(deadband.Offer(Press(f, -0.001), t0 + 1001 * kMs, &why));
  EXPECT_EQ(why, DeadbandReason::kFirst);
}

TEST(ContactSetDeadband, OffSendsEverything) {
  DeadbandConfig c;
  c.weber = 0.0;
  ContactSetDeadband deadband(c);
  for (int tick = 0; tick < 50; ++tick) EXPECT_TRUE(deadband.Offer(Press(-2.0, -0.001), tick * 10 * kMs));
  EXPECT_EQ(deadband.sent_for(DeadbandReason::kOff), 50u);
  EXPECT_EQ(deadband.reduction(), 0.0);
}

// The receiver holds the newest set; with the deadband the force it holds is never further
// from the sender's than the deadband allows: weber |f_sent| or the floor, whichever is larger.
TEST(ContactSetDeadband, TheHeldForceStaysInsideTheDeadband) {
  ContactSetDeadband deadband;
  const DeadbandConfig& c = deadband.config();
  double held = 0.0, worst_excess = -1.0;
  for (int tick = 0; tick < 2000; ++tick) {
    const double t = 0.01 * tick;
    const double f = -(1.5 + 1.4 * std::sin(2.0 * M_PI * 0.7 * t) + 0.05 * std::sin(2.0 * M_PI * 9.0 * t));
    if (deadband.Offer(Press(f, -0.001), static_cast<std::uint64_t>(tick) * 10 * kMs)) held = f;
    const double allowed = std::max(c.weber * std::abs(held), c.force_floor_N);
    worst_excess = std::max(worst_excess, std::abs(f - held) - allowed);
  }
  EXPECT_LE(worst_excess, 1e-12);
  EXPECT_GT(deadband.reduction(), 0.5);  // and it does save most of the stream
}

TEST(ContactSetDeadband, RefusesNonsense) {
  DeadbandConfig c;
  c.weber = -0.1;
  EXPECT_THROW(ContactSetDeadband{c}, std::invalid_argument);
  c.weber = 1.5;
  EXPECT_THROW(ContactSetDeadband{c}, std::invalid_argument);
  c.weber = 0.1;
  c.keepalive = std::chrono::nanoseconds(0);
  EXPECT_THROW(ContactSetDeadband{c}, std::invalid_argument);
}

}  // namespace
}  // namespace handshare::session
