// Two users pressing one body through a delayed network, in one process, 1-D: each node's
// haptic step as the haptic node runs it -- the peer's contact through the coupling's passivity
// controller (contact/coupling_passivity.hpp), the local solve, the force through ForceSafety's
// passivity observer and controller at the fingertip's port -- closed through a simulated user's
// fingertip. The cross-process version over real DDS and a delayed network is
// tests/net/net_dds_test.py's delayed_tail.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <deque>

#include "handshare/contact/coupling_passivity.hpp"
#include "handshare/haptic/force_safety.hpp"

namespace handshare::haptic {
namespace {

struct Controllers {
  bool coupling = true;  // contact::CouplingPassivity on the peer's contact
  bool port = true;      // ForceSafety's passivity controller at the fingertip
};

struct PairRun {
  double swing_m = 0.0;          // peak-to-peak of user A's fingertip over the last 2 s
  double port_energy_min_J = 0;  // lowest observed port energy (ForceSafety) of either user
  double coupling_min_J = 0.0;   // lowest coupling observer of either node
  double mean_force_N = 0.0;     // user A's force over the last 2 s
};

// Stiffness K = [[ka + kc, -kc], [-kc, kb + kc]] between the two indentations (ground springs
// ka, kb and a coupling spring kc: a stiff body pressed at two places close together). Each
// user's fingertip is a 50 g mass held at its hand's target by a light 300 N/m grip with little
// damping; each node solves the body with its own indentation and the other's as it last
// arrived (sent every 10 ms, `delay_s` later), and the user feels minus its contact's force.
PairRun RunDelayedPair(Controllers on, double delay_s) {
  const double ka = 200.0, kb = 200.0, kc = 800.0;
  const double m = 0.05, k_user = 300.0, b_user = 0.3;
  const double dt = 1e-3, sample_s = 0.01, duration_s = 10.0;
  // The body's forces at the two contacts; a contact only pushes: one that would pull lets go.
  auto forces = [&](double u1, double u2) {
    u1 = std::max(u1, 0.0);
    u2 = std::max(u2, 0.0);
    double F1 = (ka + kc) * u1 - kc * u2, F2 = -kc * u1 + (kb + kc) * u2;
    if (F2 < 0.0 || u2 == 0.0) {
      F2 = 0.0;
      F1 = (ka + kc - kc * kc / (kb + kc)) * u1;
    } else if (F1 < 0.0 || u1 == 0.0) {
      F1 = 0.0;
      F2 = (kb + kc - kc * kc / (ka + kc)) * u2;
    }
    return std::pair{F1, F2};
  };
  ForceSafetyConfig sc;
  sc.passivity = on.port;
  struct Node {
    double x = 0.0, v = 0.0, target = 0.003, F_own = 0.0;
    contact::CouplingPassivity coupling;
    std::deque<std::pair<double, contact::PeerContact>> inbox;  // (arrival time, sample)
    contact::PeerContact held;
    bool have = false;
  };
  Node node[2];
  ForceSafety safety[2] = {ForceSafety(sc), ForceSafety(sc)};
  for (Node& n : node) n.coupling.set_enabled(on.coupling);
  node[0].target = 0.004;  // user A's hand steps 1 mm deeper at the start: the pair is set going
  PairRun run;
  double lo = 1.0, hi = -1.0, f_sum = 0.0;
  int f_count = 0;
  const int steps = static_cast<int>(duration_s / dt);
  for (int n = 0; n < steps; ++n) {
    const double t = n * dt;
    const auto t_ns = static_cast<std::uint64_t>(std::llround(t * 1e9));
    for (int i = 0; i < 2; ++i) {
      Node& me = node[i];
      Node& other = node[1 - i];
      while (!me.inbox.empty() && me.inbox.front().first <= t + 1e-12) {
        me.held = me.inbox.front().second;
        me.held.received_ns = t_ns;
        me.have = true;
        me.inbox.pop_front();
      }
      double x_other = 0.0;
      me.coupling.BeginStep(dt);
      if (me.have) {
        contact::FingerContact in =
            contact::FadedContact(me.held, contact::PeerFade{1'000'000'000'000, 2'000'000'000'000}, t_ns);
        me.coupling.Admit(me.held, in);
        x_other = -in.u_O_m[2];
      }
      const auto [F_mine, F_theirs] = forces(me.x, x_other);
      const std::array<Eigen::Vector3d, 1> F = {Eigen::Vector3d(0.0, 0.0, -F_theirs)};
      me.coupling.Observe(std::span<const Eigen::Vector3d>(F.data(), me.have ? 1 : 0));
      // The fingertip (pressing along -z) feels +z; ForceSafety sees the fingertip's position.
      ForceSafetyInput in;
      in.finger[0].p_WE = Eigen::Vector3d(0.0, 0.0, -me.x);
      in.finger[0].f_desired_E_W = Eigen::Vector3d(0.0, 0.0, F_mine);
      for (int f = 1; f < kFingers; ++f) in.finger[static_cast<std::size_t>(f)].p_WE = Eigen::Vector3d(0.1 * f, 0.0, 0.1);
      ForceSafetyOutput out;
      safety[i].Step(in, out);
      const double felt = out.f_E_W[0].z();
      run.port_energy_min_J = std::min(run.port_energy_min_J, out.finger[0].observed_energy_J);
      // The user's fingertip: pulled to the target, pushed out by the felt force.
      const double a = (k_user * (me.target - me.x) - b_user * me.v - felt) / m;
      me.v += dt * a;
      me.x += dt * me.v;
      me.F_own = F_mine;
      if (n % static_cast<int>(sample_s / dt) == 0) {
        contact::PeerContact s;
        s.hand = 1;
        s.contact.object = 0;
        s.contact.u_O_m[2] = -me.x;
        s.contact.n_O[2] = 1.0;
        s.contact.f_O_N[2] = -me.F_own;  // on the body
        other.inbox.emplace_back(t + delay_s, s);
      }
      if (i == 0 && t >= duration_s - 2.0) {
        f_sum += felt;
        ++f_count;
      }
    }
    if (t >= duration_s - 2.0) {
      lo = std::min(lo, node[0].x);
      hi = std::max(hi, node[0].x);
    }
  }
  run.swing_m = hi - lo;
  run.coupling_min_J = std::min(node[0].coupling.stats().observer_min_J, node[1].coupling.stats().observer_min_J);
  run.mean_force_N = f_sum / std::max(f_count, 1);
  return run;
}

void Print(const char* what, double delay_s, const PairRun& r) {
  std::printf("delay %3.0f ms, %-34s swing %8.4f mm, force %.3f N, port energy min %.2e J, coupling observer min %.2e J\n",
              1e3 * delay_s, what, 1e3 * r.swing_m, r.mean_force_N, r.port_energy_min_J, r.coupling_min_J);
}

TEST(CouplingStability, TwoDelayedUsersOnOneBodyOscillateWithoutTheControllersAndSettleWithThem) {
  const PairRun ref = RunDelayedPair({}, 0.0);
  Print("both controllers", 0.0, ref);
  EXPECT_LT(ref.swing_m, 1e-4);
  for (const double delay_s : {0.01, 0.025, 0.05, 0.1}) {
    SCOPED_TRACE(delay_s);
    const PairRun none = RunDelayedPair({false, false}, delay_s);
    const PairRun coupling = RunDelayedPair({true, false}, delay_s);
    const PairRun port = RunDelayedPair({false, true}, delay_s);
    const PairRun both = RunDelayedPair({true, true}, delay_s);
    Print("no controller", delay_s, none);
    Print("coupling controller only", delay_s, coupling);
    Print("port controller only (default)", delay_s, port);
    Print("both controllers", delay_s, both);
    if (delay_s >= 0.025) {
      EXPECT_GT(none.swing_m, 1e-3);  // sustained: a millimetre and more, 8 s after the step
    }
    EXPECT_LT(both.swing_m, 1e-4);  // settled: under 0.1 mm (a 3 mm press; without: 2-36 mm)
    EXPECT_LT(port.swing_m, 1e-4);  // the default (the coupling's controller off) settles too
    EXPECT_GE(both.coupling_min_J, -1e-6);
    // What the user ends up feeling is the no-delay force, to the drift the controller left.
    EXPECT_NEAR(both.mean_force_N, ref.mean_force_N, 0.05 * ref.mean_force_N);
  }
}

}  // namespace
}  // namespace handshare::haptic
