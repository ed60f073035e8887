// Friction on the real triceratops tail (the dinosaur scene's mesh, tetrahedralized and
// precomputed as every node does it, with mu set on its material): a fingertip pressed into
// the tail and stroked along it toward the tip slips, and while it slips the tangential force it
// feels is mu_kinetic times the normal force (the bound asked for: 5%), against the stroke.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/contact/coupling_passivity.hpp"
#include "handshare/scene/scene.hpp"
#include "handshare/world/scene_models.hpp"
#include "test_models.hpp"

namespace handshare::world {
namespace {

// The dinosaur scene reduced to its tail, with these friction coefficients on its material;
// with `stiffening`, the tail's committed stiffening table on (docs/fem.md, "A correction
// beyond the paper").
scene::Scene TailScene(double mu_static, double mu_kinetic, bool stiffening = false) {
  scene::Scene s = test::OneDeformable("dinosaur.json", "triceratops_tail");
  s.objects[0].deformable.mu_static = mu_static;
  s.objects[0].deformable.mu_kinetic = mu_kinetic;
  if (stiffening) {
    s.objects[0].deformable.stiffening_table_path =
        std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "meshes" / "triceratops_tail.stiffening.csv";
  }
  return s;
}

// The tail's models, prepared once into HANDSHARE_CACHE (else a folder of the temp dir).
SceneModels BuildTail(const scene::Scene& s) { return test::BuildCached(s, "handshare_tail_friction_cache"); }

// A fingertip centre (frame O) 3 mm above the highest surface node of the tail near `fraction`
// of the way from its attached base to its tip.
Eigen::Vector3d AboveTheTop(const SceneModels& sw, double fraction) {
  const PreparedDeformable& tail = sw.deformables[0];
  double x_min = 0.0;
  for (const auto& p : tail.mesh->positions_m()) x_min = std::min(x_min, p.x());
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  double z_top = -std::numeric_limits<double>::infinity();
  for (std::int32_t v : tail.surface->nodes) {
    const Eigen::Vector3d& p = tail.mesh->positions_m()[static_cast<std::size_t>(v)];
    if (std::abs(p.x() - fraction * x_min) < 0.004 && p.z() > z_top) {
      z_top = p.z();
      at = p;
    }
  }
  if (!std::isfinite(z_top)) throw std::runtime_error("no surface node of the tail there");
  at.z() += sw.world->config().fingertip_radius_m + 0.003;
  return at;
}

// One fingertip (the index) over the tail with these coefficients, its centre tip_O (frame O)
// starting 3 mm above the top at `fraction` of the way to the tip (AboveTheTop); the other
// fingertips far away.
struct OneFingertipOnTheTail {
  OneFingertipOnTheTail(double mu_static, double mu_kinetic, double fraction)
      : scene(TailScene(mu_static, mu_kinetic)), models(BuildTail(scene)), X_WO(scene.objects[0].X_WO()),
        tip_O(AboveTheTop(models, fraction)) {
    tips.fill(Eigen::Vector3d(5, 5, 5));
  }
  // One 1 ms step with the index at tip_O; what it feels.
  const contact::FingerResult& Step() {
    tips[1] = X_WO * tip_O;
    models.world->Step(1e-3, tips);
    return models.world->fingers()[1];
  }
  scene::Scene scene;
  SceneModels models;
  Eigen::Isometry3d X_WO;
  Eigen::Vector3d tip_O;
  std::array<Eigen::Vector3d, 5> tips;
};

TEST(TailFriction, AFingerStrokingTheTailDragsWithMuTimesTheNormalForce) {
  const double mu_s = 0.8, mu_k = 0.6;
  const scene::Scene s = TailScene(mu_s, mu_k);
  SceneModels sw = BuildTail(s);
  ASSERT_EQ(sw.deformables.size(), 1u);
  const PreparedDeformable& tail = sw.deformables[0];
  const Eigen::Isometry3d X_WO = s.objects[0].X_WO();
  // The tail runs from its attached base (x > -5 mm in O) toward -x. Stroke its top half way
  // along, where it is thick: the highest surface node near (x0, y0) is the top.
  double x_min = 0.0;
  for (const auto& p : tail.mesh->positions_m()) x_min = std::min(x_min, p.x());
  const double x0 = 0.45 * x_min;
  double y_sum = 0.0, z_top = -std::numeric_limits<double>::infinity();
  int near = 0;
  for (std::int32_t v : tail.surface->nodes) {
    const Eigen::Vector3d& p = tail.mesh->positions_m()[static_cast<std::size_t>(v)];
    if (std::abs(p.x() - x0) > 0.004) continue;
    y_sum += p.y();
    ++near;
  }
  ASSERT_GT(near, 4);
  const double y0 = y_sum / near;
  // Start right above the highest surface node there (the surface nodes are several mm apart).
  double xs = x0, ys = y0;
  for (std::int32_t v : tail.surface->nodes) {
    const Eigen::Vector3d& p = tail.mesh->positions_m()[static_cast<std::size_t>(v)];
    if (std::hypot(p.x() - x0, p.y() - y0) < 0.006 && p.z() > z_top) {
      z_top = p.z();
      xs = p.x();
      ys = p.y();
    }
  }
  ASSERT_TRUE(std::isfinite(z_top));
  const double R = sw.world->config().fingertip_radius_m;
  std::array<Eigen::Vector3d, 5> tips;
  for (auto& p : tips) p = Eigen::Vector3d(5, 5, 5);
  // Down from 3 mm above to 4 mm deep (about 2 N) in 100 steps, then 10 mm toward the tail's
  // tip at 20 mm/s.
  Eigen::Vector3d tip_O(xs, ys, z_top + R + 0.003);
  for (int k = 0; k < 100; ++k) {
    tip_O.z() -= 0.007 / 100;
    tips[1] = X_WO * tip_O;
    sw.world->Step(1e-3, tips);
  }
  ASSERT_TRUE(sw.world->fingers()[1].in_contact);
  const Eigen::Vector3d stroke_W = X_WO.linear() * -Eigen::Vector3d::UnitX();
  int slipping = 0, measured = 0, paused = 0;
  double worst = 0.0, first_slip_mm = -1.0;
  Eigen::Vector3d contact_before = sw.world->fingers()[1].p_WC_m;
  for (int k = 1; k <= 500; ++k) {
    tip_O.x() -= 20e-6;
    tips[1] = X_WO * tip_O;
    const contact::StepReport rep = sw.world->Step(1e-3, tips);
    const contact::FingerResult& r = sw.world->fingers()[1];
    ASSERT_TRUE(r.in_contact) << k;
    const double fn = r.f_E_W_N.dot(r.n_W);
    const Eigen::Vector3d ft = r.f_E_W_N - fn * r.n_W;
      ASSERT_GT(fn, 0.0) << k << ": f " << r.f_E_W_N.transpose() << ", " << r.patch_nodes << " patch nodes, "
                       << rep.solver_faults << " solver faults";
    if (!r.sticking && first_slip_mm < 0.0) first_slip_mm = k * 0.02;
    // Where the proxy pauses for a step or two (at an edge of the tail's triangles), its contact
    // point does not move over the surface: the patch holds there (it sticks, inside its cone).
    const bool moved = (r.p_WC_m - contact_before).norm() > 1e-6;
    contact_before = r.p_WC_m;
    if (k <= 250) continue;  // well into the stroke
    if (!moved) {
      ++paused;
      EXPECT_LE(ft.norm(), mu_k * fn * (1 + 1e-9)) << k;
      continue;
    }
    ++measured;
    slipping += r.sticking ? 0 : 1;
    EXPECT_LT(ft.dot(stroke_W), 0.0) << k;  // against the stroke
    worst = std::max(worst, std::abs(ft.norm() / fn - mu_k) / mu_k);
  }
  RecordProperty("stick_length_mm", std::to_string(first_slip_mm));
  RecordProperty("worst_ratio_error", std::to_string(worst));
  RecordProperty("steps_the_proxy_paused", std::to_string(paused));
  EXPECT_LT(paused, 25);
  // (Pressed straight down on the sloping top, the patch sticks a tenth of the way to its
  // cone; the stroke's first 1-2 mm lean it on the cone, then it slips: measured from 5 mm on.)
  EXPECT_EQ(slipping, measured);
  EXPECT_LT(worst, 0.05);
}


// With one coefficient for sticking and slipping (0.7, the one meant for the scene's
// triceratops: docs/scenes.md), a fingertip that creeps over the tail slower than the solve's
// rest threshold (1 um a step) slips without a jump. Pressed 4 mm into the top at 40 % of the
// way to the tip it sticks (a tenth of its cone), then creeps toward the tip at 0.5 mm/s for
// 5 s: its stick grows until the patch leans on its cone and slips a little each step, and the
// direction of its force is the one its slide agrees with, found exactly (ContactSolver). No
// step (1 ms) that sticks or slips on changes the force on the fingertip by more than 5 % of
// its normal force. Before, that direction came from a fixed point that diverges when the slip
// is small: when its 16 rounds ran out it was anywhere, and the creep jumped by 0.3 to 1.1 N
// (up to 112 % of F_n) in single steps. A step in which a slipping patch sticks again is not
// held to it: its held set can drop a node that carried tangential force but no pressure
// (docs/fem.md, "Limits"); the largest such step is recorded.
TEST(TailFriction, AFingertipCreepingOverTheTailSlipsWithoutAJump) {
  const double mu_s = 0.7, mu_k = 0.7;
  OneFingertipOnTheTail t(mu_s, mu_k, 0.4);
  for (int k = 0; k < 300; ++k) {  // down 7 mm in 100 steps (4 mm in), held for 0.2 s
    if (k < 100) t.tip_O.z() -= 0.007 / 100;
    t.Step();
  }
  ASSERT_TRUE(t.models.world->fingers()[1].in_contact);
  Eigen::Vector3d f_prev = t.models.world->fingers()[1].f_E_W_N;
  double worst = 0.0;  // the largest step's share of the normal force
  bool stuck = t.models.world->fingers()[1].sticking, slipped = false;
  double worst_restick = 0.0;  // the same, over the steps in which a slipping patch sticks again
  int slipping_steps = 0;
  for (int k = 0; k < 5000; ++k) {  // 2.5 mm toward the tip at 0.5 mm/s
    t.tip_O.x() -= 0.5e-6;
    const bool was_sticking = t.models.world->fingers()[1].sticking;
    const contact::FingerResult& r = t.Step();
    ASSERT_TRUE(r.in_contact) << k;
    const double fn = r.f_E_W_N.dot(r.n_W);
    ASSERT_GT(fn, 0.1) << k;
    const double step = (r.f_E_W_N - f_prev).norm() / fn;
    if (!was_sticking && r.sticking) {
      worst_restick = std::max(worst_restick, step);
    } else {
      worst = std::max(worst, step);
    }
    slipping_steps += r.sticking ? 0 : 1;
    stuck = stuck || r.sticking;
    slipped = slipped || (stuck && !r.sticking);
    f_prev = r.f_E_W_N;
  }
  RecordProperty("mu_static", std::to_string(mu_s));
  RecordProperty("mu_kinetic", std::to_string(mu_k));
  RecordProperty("slipping_steps", std::to_string(slipping_steps));
  RecordProperty("largest_step_over_normal_force", std::to_string(worst));
  RecordProperty("largest_step_sticking_again_over_normal_force", std::to_string(worst_restick));
  EXPECT_TRUE(slipped) << "the creep should break the stick it started with";
  EXPECT_LT(worst, 0.05);
}

// A fingertip pressed 2 mm into the top of the tail, drawn 1.5 mm sideways (its patch sticks,
// leaning a third of the way to its cone) and then pressed 3 mm deeper at 10 mm/s: as its
// footprint grows, nodes join the sticking patch. No step changes the force on the fingertip by
// more than 5 % of its normal force. Before, a sticking patch under a moving fingertip was
// checked against its cone on the first trial of every solve, which holds the joining nodes
// that pull: the patch slipped at 0.49 of its normal force (its cone 0.7) and its force turned
// to the fingertip's motion in one step, 0.49 N at 0.75 N pressing (65 % of F_n).
TEST(TailFriction, NodesJoiningAStickingPatchUnderAMovingFingertipDoNotSlipIt) {
  const double mu = 0.7;
  OneFingertipOnTheTail t(mu, mu, 0.4);
  Eigen::Vector3d f_prev = Eigen::Vector3d::Zero();
  int nodes_before = 0, nodes_after = 0;
  double worst = 0.0, largest_cone_share = 0.0;
  for (int k = 0; k < 800; ++k) {
    if (k < 100) {
      t.tip_O.z() -= 0.005 / 100;  // 2 mm in
    } else if (k >= 200 && k < 500) {
      t.tip_O.y() += 1.5e-3 / 300;  // 1.5 mm sideways at 5 mm/s
    } else if (k >= 500) {
      t.tip_O.z() -= 3e-3 / 300;  // 3 mm deeper at 10 mm/s
    }
    const contact::FingerResult& r = t.Step();
    ASSERT_TRUE(k < 100 || r.in_contact) << k;
    const double fn = r.f_E_W_N.dot(r.n_W);
    if (k == 499) nodes_before = r.patch_nodes;
    if (k >= 500) {
      ASSERT_GT(fn, 0.1) << k;
      worst = std::max(worst, (r.f_E_W_N - f_prev).norm() / fn);
      largest_cone_share = std::max(largest_cone_share, (r.f_E_W_N - fn * r.n_W).norm() / (mu * fn));
      nodes_after = r.patch_nodes;
    }
    f_prev = r.f_E_W_N;
  }
  RecordProperty("patch_nodes_before_and_after", std::to_string(nodes_before) + " -> " + std::to_string(nodes_after));
  RecordProperty("largest_share_of_the_cone", std::to_string(largest_cone_share));
  RecordProperty("largest_step_over_normal_force", std::to_string(worst));
  EXPECT_GT(nodes_after, nodes_before + 1) << "the deeper press should add nodes to the patch";
  EXPECT_LT(worst, 0.05);
}

// One random stroke (RandomStrokesOverTheTailMostlyGlide): where along the tail's top the
// fingertip presses, how deep, and how it is drawn over it.
struct RandomStroke {
  explicit RandomStroke(std::mt19937& rng) {
    std::uniform_real_distribution<double> uniform(0.0, 1.0);
    fraction = 0.2 + 0.4 * uniform(rng);
    dy = 0.004 * (uniform(rng) - 0.5);
    depth = 0.003 + 0.003 * uniform(rng);
    angle = 2 * M_PI * uniform(rng);
    speed = std::pow(10.0, -0.5 + 1.8 * uniform(rng)) * 1e-6;  // per step
    sink = (uniform(rng) - 0.3) * 3e-6;                        // per step
  }
  // A fingertip on a fresh tail where this stroke starts.
  OneFingertipOnTheTail Fingertip(double mu) const {
    OneFingertipOnTheTail t(mu, mu, fraction);
    t.tip_O.y() += dy;
    return t;
  }
  // Moves the fingertip for step k of kSteps: pressed in over 100 steps, held, drawn over the
  // tail from step 300 to 1100, held again.
  static constexpr int kSteps = 1400;
  void Move(OneFingertipOnTheTail& t, int k) const {
    if (k < 100) {
      t.tip_O.z() -= (0.003 + depth) / 100;
    } else if (k >= 300 && k < 1100) {
      t.tip_O += Eigen::Vector3d(speed * std::cos(angle), speed * std::sin(angle), -sink);
    }
  }
  double fraction, dy, depth, angle, speed, sink;
};

// Thirty fingertips pressed 3-6 mm into the tail's top at random places along it and drawn
// over it at random (a direction, 0.3-20 mm/s, sinking or rising a little) for 0.8 s, then
// held for 0.3 s, each alone on a fresh tail with the scene's coefficient (0.7). Each stroke's
// largest step (1 ms, after the press) over the normal force is measured; in the median stroke
// it stays under 1 % of F_n. Before a sticking patch under a moving fingertip decided on its
// settled held set, the median stroke's largest step was 34 % of F_n (18 of these 30 strokes
// over 5 %). Strokes still step by more than 5 % (docs/fem.md, "Limits": a node that carries
// tangential force but no pressure, a stroke's slip turning to the motion's direction): their
// share is recorded.
TEST(TailFriction, RandomStrokesOverTheTailMostlyGlide) {
  const double mu = 0.7;
  std::mt19937 rng(11);
  constexpr int kStrokes = 30;
  std::vector<double> worsts;
  for (int c = 0; c < kStrokes; ++c) {
    const RandomStroke stroke(rng);
    OneFingertipOnTheTail t = stroke.Fingertip(mu);
    Eigen::Vector3d f_prev = Eigen::Vector3d::Zero();
    double worst = 0.0;
    for (int k = 0; k < RandomStroke::kSteps; ++k) {
      stroke.Move(t, k);
      const contact::FingerResult& r = t.Step();
      if (k >= 150 && r.in_contact) {
        const double fn = r.f_E_W_N.dot(r.n_W);
        worst = std::max(worst, (r.f_E_W_N - f_prev).norm() / std::max(fn, 0.1));
      }
      f_prev = r.f_E_W_N;
    }
    worsts.push_back(worst);
  }
  std::sort(worsts.begin(), worsts.end());
  const auto over = std::count_if(worsts.begin(), worsts.end(), [](double w) { return w > 0.05; });
  RecordProperty("median_largest_step_over_normal_force", std::to_string(worsts[kStrokes / 2]));
  RecordProperty("strokes_with_a_step_over_5_percent", std::to_string(over) + " of " + std::to_string(kStrokes));
  RecordProperty("largest_step_over_normal_force", std::to_string(worsts.back()));
  EXPECT_LT(worsts[kStrokes / 2], 0.01);
}

// A fingertip pressed 4 mm into the sloping top of the tail and then held still comes to rest:
// its patch slips to its cone and sticks there. Before a slipping patch under a fingertip at
// rest took its direction from its slide (kinetic friction opposes the sliding), it kept the
// trial force's direction and never came to rest: its stick crept about 0.7 mm a step and
// jumped back, 1.35 mm in one step within the last second of holding (docs/fem.md).
TEST(TailFriction, AFingertipHeldStillOnTheTailComesToRest) {
  OneFingertipOnTheTail t(0.8, 0.6, 0.35);  // 35 % of the way to the tip
  // Down 7 mm in 100 steps (4 mm into the tail), then held still for 2 s.
  Eigen::Vector3d u_prev = Eigen::Vector3d::Zero();
  double largest_late_change_m = 0.0;
  for (int k = 0; k < 2100; ++k) {
    if (k < 100) t.tip_O.z() -= 0.007 / 100;
    const contact::FingerResult& r = t.Step();
    ASSERT_TRUE(k < 100 || r.in_contact) << k;
    if (k >= 1100) largest_late_change_m = std::max(largest_late_change_m, (r.u_W_m - u_prev).norm());
    u_prev = r.u_W_m;
  }
  RecordProperty("largest_change_per_step_in_the_last_second_um", std::to_string(1e6 * largest_late_change_m));
  // At rest after a second of holding: the imposed displacement no longer changes (1 um a step).
  EXPECT_LT(largest_late_change_m, 1e-6);
}


// The network between two haptic nodes, one way: the sender's contacts every 10 ms, delivered
// delay_ms later and held until the next (zero-order hold), faded as they age (PeerFade),
// through the receiver's coupling passivity controller (contact::CouplingPassivity, on as by
// default). From a cut on nothing more arrives: what is held fades out.
struct DelayedLink {
  std::vector<std::pair<int, std::vector<contact::FingerContact>>> in_flight;
  std::vector<contact::PeerContact> held;
  contact::CouplingPassivity passivity;
  std::vector<contact::FingerContact> Deliver(int k, const std::vector<contact::FingerContact>& sent, int delay_ms,
                                              bool cut = false) {
    const std::uint64_t now_ns = 1'000'000ull * static_cast<std::uint64_t>(k + 1);
    if (cut) in_flight.clear();
    if (k % 10 == 0 && !cut) in_flight.emplace_back(k + delay_ms, sent);
    while (!in_flight.empty() && in_flight.front().first <= k) {
      held.clear();
      for (const auto& r : in_flight.front().second) {
        contact::PeerContact c;
        c.hand = 1;
        c.contact = r;
        c.received_ns = now_ns;
        held.push_back(c);
      }
      in_flight.erase(in_flight.begin());
    }
    std::vector<contact::FingerContact> out;
    passivity.BeginStep(1e-3);
    for (const auto& c : held) {
      out.push_back(contact::FadedContact(c, contact::PeerFade{}, now_ns));
      passivity.Admit(c, out.back());
    }
    return out;
  }
};

// What a contact set carries of a fingertip that touches (one contact, hand 1, finger 1).
std::vector<contact::FingerContact> Sent(const contact::FingerResult& r) {
  std::vector<contact::FingerContact> v;
  if (r.in_contact) {
    v.push_back(r.contact);
    v.back().finger = 1;
  }
  return v;
}

// Two worlds, as two haptic nodes on one tail, each with one fingertip held still in it,
// exchange their contacts every step (what their contact sets carry).
struct TwoHandsResult {
  double alice_force_N = 0.0;
  double largest_late_change_m = 0.0;   // of either fingertip's imposed displacement, per step
  double largest_late_change_N = 0.0;   // of the force either fingertip feels, per step
};

// Alice's fingertip above the top at the fraction at_a of the way to the tail's tip, bob's at
// at_b (negative: bob stays away). A device's jitter: every fingertip position gets a normal
// error of jitter_m a coordinate, every step.
// With delay_ms >= 0 the contacts cross a network as the haptic nodes exchange them: a sample
// every 10 ms, delivered delay_ms later, held until the next (zero-order hold), through each
// receiver's coupling passivity controller (contact::CouplingPassivity, on as by default).
TwoHandsResult HoldTheTailWithTwoHands(double mu_static, double mu_kinetic, double at_a = 0.35, double at_b = 0.55,
                                       double jitter_m = 0.0, int delay_ms = -1,
                                       contact::CouplingPassivityStats* coupling = nullptr, bool stiffening = false) {
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1.0);
  const scene::Scene s = TailScene(mu_static, mu_kinetic, stiffening);
  SceneModels alice = BuildTail(s);
  SceneModels bob = BuildTail(s);
  const Eigen::Isometry3d X_WO = s.objects[0].X_WO();
  Eigen::Vector3d tip_a = AboveTheTop(alice, at_a);
  Eigen::Vector3d tip_b = at_b < 0.0 ? Eigen::Vector3d::Zero() : AboveTheTop(alice, at_b);  // bob away: unused
  std::array<Eigen::Vector3d, 5> tips_a, tips_b;
  tips_a.fill(Eigen::Vector3d(5, 5, 5));
  tips_b.fill(Eigen::Vector3d(5, 5, 5));
  std::vector<contact::FingerContact> from_alice, from_bob;
  DelayedLink at_alice, at_bob;
  TwoHandsResult out;
  contact::FingerResult a_prev, b_prev;
  for (int k = 0; k < 2100; ++k) {  // down 7 mm in 100 steps (4 mm in), then held for 2 s
    if (k < 100) {
      tip_a.z() -= 0.007 / 100;
      tip_b.z() -= 0.007 / 100;
    }
    tips_a[1] = X_WO * tip_a + jitter_m * Eigen::Vector3d(noise(rng), noise(rng), noise(rng));
    tips_b[1] = at_b < 0.0 ? Eigen::Vector3d(5, 5, 5) : Eigen::Vector3d(X_WO * tip_b + jitter_m * Eigen::Vector3d(noise(rng), noise(rng), noise(rng)));  // bob away
    if (delay_ms < 0) {
      alice.world->Step(1e-3, tips_a, from_bob);
      bob.world->Step(1e-3, tips_b, from_alice);
    } else {
      const auto in_a = at_alice.Deliver(k, from_bob, delay_ms);
      const auto in_b = at_bob.Deliver(k, from_alice, delay_ms);
      alice.world->Step(1e-3, tips_a, in_a);
      at_alice.passivity.Observe(alice.world->remote_forces_O());
      bob.world->Step(1e-3, tips_b, in_b);
      at_bob.passivity.Observe(bob.world->remote_forces_O());
    }
    const contact::FingerResult& a = alice.world->fingers()[1];
    const contact::FingerResult& b = bob.world->fingers()[1];
    from_alice = Sent(a);
    from_bob = Sent(b);
    if (k >= 1100) {  // the last second
      out.largest_late_change_m = std::max({out.largest_late_change_m, (a.u_W_m - a_prev.u_W_m).norm(),
                                            (b.u_W_m - b_prev.u_W_m).norm()});
      out.largest_late_change_N = std::max({out.largest_late_change_N, (a.f_E_W_N - a_prev.f_E_W_N).norm(),
                                            (b.f_E_W_N - b_prev.f_E_W_N).norm()});
    }
    a_prev = a;
    b_prev = b;
    out.alice_force_N = a.f_E_W_N.norm();
  }
  if (coupling != nullptr) {
    *coupling = at_alice.passivity.stats();
    const auto& b = at_bob.passivity.stats();
    coupling->held_back += b.held_back;
    coupling->drift_max_m = std::max(coupling->drift_max_m, b.drift_max_m);
    coupling->energy_granted_J += b.energy_granted_J;
    coupling->observer_min_J = std::min(coupling->observer_min_J, b.observer_min_J);
  }
  return out;
}

// With friction each fingertip still feels its press. Before a fingertip re-anchored where its
// anchor had no node under it, alice's slid off her footprint in the first steps, her patch
// came out empty from then on and she felt 0 N at 4 mm deep (1.34 N without friction).
TEST(TailFriction, TwoHandsHeldStillOnTheTailBothFeelTheirPress) {
  const TwoHandsResult frictionless = HoldTheTailWithTwoHands(0.0, 0.0);
  const TwoHandsResult friction = HoldTheTailWithTwoHands(0.8, 0.6);
  RecordProperty("alice_force_frictionless_N", std::to_string(frictionless.alice_force_N));
  RecordProperty("alice_force_friction_N", std::to_string(friction.alice_force_N));
  ASSERT_GT(frictionless.alice_force_N, 1.0);
  EXPECT_LT(frictionless.largest_late_change_m, 1e-6);
  // Friction changes the force's direction a little, not whether the fingertip is pushed back.
  EXPECT_GT(friction.alice_force_N, 0.7 * frictionless.alice_force_N);
}

// Held still anywhere along the tail, one fingertip or two (two worlds exchanging contacts)
// come to rest: in the last second neither fingertip's imposed displacement changes by 1 um a
// step, nor its force by 1 mN. Before a patch at rest was checked against its cone on a settled
// held set (ContactSolver), 21 of these 22 pairs never did (alice's stick jumped by 1 mm every
// step at 0.35/0.55), nor 4 of these 12 single fingertips (up to 2.5 mm a step). So the three
// cross-process cases where two users hold the tail never saw it still (docs/scenes.md).
// Held by devices that jitter (2 um a coordinate and step, white: above the HIRO II model's
// 1.3 um p50 a step), they stay within 30 um and 30 mN a step. Before the fingertip's motion
// was smoothed (HapticWorld), that jitter was taken for strokes and 19 of the 22 pairs jumped
// by up to 7 mm a step; the HIRO II user of session.encyclopedia never let the tail come to
// rest (1 run in 2).
TEST(TailFriction, HandsHeldStillAnywhereAlongTheTailComeToRest) {
  int pairs = 0, single = 0;
  for (double a : {0.1, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6, 0.7, 0.8}) {
    const TwoHandsResult r = HoldTheTailWithTwoHands(0.8, 0.6, a, -1.0);
    EXPECT_LT(r.largest_late_change_m, 1e-6) << "one hand at " << a;
    EXPECT_LT(r.largest_late_change_N, 1e-3) << "one hand at " << a;
    EXPECT_GT(r.alice_force_N, 0.1) << a;
    ++single;
  }
  double jittered_m = 0.0, jittered_N = 0.0;
  for (double a : {0.2, 0.3, 0.35, 0.4, 0.5}) {
    for (double b : {0.45, 0.55, 0.6, 0.7, 0.8}) {
      if (b <= a + 0.05) continue;
      const TwoHandsResult r = HoldTheTailWithTwoHands(0.8, 0.6, a, b);
      EXPECT_LT(r.largest_late_change_m, 1e-6) << "hands at " << a << " and " << b;
      EXPECT_LT(r.largest_late_change_N, 1e-3) << "hands at " << a << " and " << b;
      const TwoHandsResult j = HoldTheTailWithTwoHands(0.8, 0.6, a, b, 2e-6);
      EXPECT_LT(j.largest_late_change_m, 30e-6) << "jittering hands at " << a << " and " << b;
      EXPECT_LT(j.largest_late_change_N, 30e-3) << "jittering hands at " << a << " and " << b;
      jittered_m = std::max(jittered_m, j.largest_late_change_m);
      jittered_N = std::max(jittered_N, j.largest_late_change_N);
      ++pairs;
    }
  }
  RecordProperty("jittering_pairs_largest_change_per_step_um", std::to_string(1e6 * jittered_m));
  RecordProperty("jittering_pairs_largest_force_change_per_step_mN", std::to_string(1e3 * jittered_N));
  EXPECT_EQ(single, 12);
  EXPECT_EQ(pairs, 22);
}

// The same pairs across a delayed network with the coupling's passivity controller (on by
// default in the haptic nodes) between them: they come to rest too, and the controller never
// holds anything back here. (A cross-process run with friction in the scenes once saw the tail
// never at rest, the controller holding alice's contact back at bob's node by 2.6 mm; this
// in-process pair at 0-50 ms does not reproduce that: docs/scenes.md.)
TEST(TailFriction, HandsHeldStillAcrossADelayComeToRest) {
  for (int delay : {0, 20, 50}) {
    for (double a : {0.2, 0.35}) {
      for (double b : {0.45, 0.55}) {
        contact::CouplingPassivityStats c;
        const TwoHandsResult r = HoldTheTailWithTwoHands(0.8, 0.6, a, b, 0.0, delay, &c);
        std::printf("delay %d ms, hands at %.2f and %.2f: late change %.2e m %.2e N, held back %llu, drift %.3f mm, "
                    "granted %.2e J, observer min %.2e J, alice %.3f N\n",
                    delay, a, b, r.largest_late_change_m, r.largest_late_change_N,
                    static_cast<unsigned long long>(c.held_back), 1e3 * c.drift_max_m, c.energy_granted_J,
                    c.observer_min_J, r.alice_force_N);
        EXPECT_LT(r.largest_late_change_m, 1e-6) << delay << " ms, hands at " << a << " and " << b;
        EXPECT_LT(r.largest_late_change_N, 1e-3) << delay << " ms, hands at " << a << " and " << b;
      }
    }
  }
}

// Issue 47's two-user delayed press with the stiffening correction on (it scales each patch's
// force, the hand's own and the peer's rebuilt one): the pair of HandsHeldStillAcrossADelay at
// 0 and 50 ms still comes to rest, and the coupling's passivity observer stays within the bound
// net.delayed_tail holds it to (-1e-4 J). The table must really be on: alice feels a different
// force than without it (else this would only repeat the test above).
TEST(TailFriction, HandsHeldStillAcrossADelayWithTheStiffeningTableComeToRest) {
  for (int delay : {0, 50}) {
    contact::CouplingPassivityStats c_lin, c;
    const TwoHandsResult lin = HoldTheTailWithTwoHands(0.8, 0.6, 0.35, 0.55, 0.0, delay, &c_lin, false);
    const TwoHandsResult r = HoldTheTailWithTwoHands(0.8, 0.6, 0.35, 0.55, 0.0, delay, &c, true);
    std::printf("delay %d ms, stiffening table on: late change %.2e m %.2e N, held back %llu, granted %.2e J, "
                "observer min %.2e J (linear %.2e J), alice %.4f N (linear %.4f N)\n",
                delay, r.largest_late_change_m, r.largest_late_change_N, static_cast<unsigned long long>(c.held_back),
                c.energy_granted_J, c.observer_min_J, c_lin.observer_min_J, r.alice_force_N, lin.alice_force_N);
    EXPECT_GT(std::abs(r.alice_force_N / lin.alice_force_N - 1.0), 1e-3) << delay << " ms: the table is not applied";
    EXPECT_LT(r.largest_late_change_m, 1e-6) << delay << " ms";
    EXPECT_LT(r.largest_late_change_N, 1e-3) << delay << " ms";
    EXPECT_GE(c.observer_min_J, -1e-4) << delay << " ms";
  }
}

// net.partitioned_user in process: alice's and bob's index fingertips come in as the simulated
// hands bring them (minimum jerk over 1.5 s, alice 0.2 s ahead) and press the scene's tail
// (0.7) together, their contacts crossing a 15 ms link every 10 ms; then the link is cut and
// each one's copy of the other's contact fades out over 0.3 s. Both forces move to their
// alone-values as ramps: no 1 ms step over 0.01 N (the fade moves them by up to 3 mN a step).
// Before a peer's patch had the material's cone, it held its sent stick whatever the force:
// bob's fading patch in alice's world kept 0.29 N along the surface on one node with 0.07 N of
// push left, and when that node let go, alice's force stepped by 0.063 N in one step.
TEST(TailFriction, APeersFadingPressLetsGoWithoutAStep) {
  const scene::Scene s = TailScene(0.7, 0.7);
  SceneModels alice = BuildTail(s);
  SceneModels bob = BuildTail(s);
  std::array<Eigen::Vector3d, 5> tips_a, tips_b;
  tips_a.fill(Eigen::Vector3d(5, 5, 5));
  tips_b.fill(Eigen::Vector3d(5, 5, 5));
  // Where the cross-process case's scripts bring the index fingertips (frame W).
  const Eigen::Vector3d a0(0.189, 0.18, 0.10), a1(0.225, 0.08, 0.0649);
  const Eigen::Vector3d b0(0.234, 0.18, 0.11), b1(0.27, 0.08, 0.0785);
  auto min_jerk = [](double t) { return t <= 0 ? 0 : (t >= 1 ? 1 : t * t * t * (10 - 15 * t + 6 * t * t)); };
  constexpr int kCut = 4000, kEnd = 5200, kDelay = 15;
  std::vector<contact::FingerContact> from_alice, from_bob;
  DelayedLink at_alice, at_bob;
  std::vector<double> fa(kEnd), fb(kEnd);
  for (int k = 0; k < kEnd; ++k) {
    tips_a[1] = a0 + min_jerk((k + 200) / 1500.0) * (a1 - a0);
    tips_b[1] = b0 + min_jerk(k / 1500.0) * (b1 - b0);
    const auto in_a = at_alice.Deliver(k, from_bob, kDelay, k >= kCut);
    const auto in_b = at_bob.Deliver(k, from_alice, kDelay, k >= kCut);
    alice.world->Step(1e-3, tips_a, in_a);
    at_alice.passivity.Observe(alice.world->remote_forces_O());
    bob.world->Step(1e-3, tips_b, in_b);
    at_bob.passivity.Observe(bob.world->remote_forces_O());
    from_alice = Sent(alice.world->fingers()[1]);
    from_bob = Sent(bob.world->fingers()[1]);
    fa[k] = alice.world->fingers()[1].f_E_W_N.z();
    fb[k] = bob.world->fingers()[1].f_E_W_N.z();
  }
  auto mean = [](const std::vector<double>& f, int from, int to) {
    double m = 0.0;
    for (int k = from; k < to; ++k) m += f[k];
    return m / (to - from);
  };
  auto largest_step = [&](const std::vector<double>& f) {
    double w = 0.0;
    for (int k = kCut - 500; k + 1 < kEnd; ++k) w = std::max(w, std::abs(f[k + 1] - f[k]));
    return w;
  };
  const double a_before = mean(fa, kCut - 1000, kCut - 100), a_alone = mean(fa, kEnd - 300, kEnd);
  const double b_before = mean(fb, kCut - 1000, kCut - 100), b_alone = mean(fb, kEnd - 300, kEnd);
  RecordProperty("alice_N", std::to_string(a_before) + " -> " + std::to_string(a_alone));
  RecordProperty("bob_N", std::to_string(b_before) + " -> " + std::to_string(b_alone));
  RecordProperty("alice_largest_step_N", std::to_string(largest_step(fa)));
  RecordProperty("bob_largest_step_N", std::to_string(largest_step(fb)));
  // Each felt the other: the cut changes both forces by far more than a step may.
  ASSERT_GT(std::abs(a_alone - a_before), 0.1);
  ASSERT_GT(std::abs(b_alone - b_before), 0.1);
  EXPECT_LT(largest_step(fa), 0.01);
  EXPECT_LT(largest_step(fb), 0.01);
}

// What a peer or the world server solves from a contact set is what its sender felt: 30
// random strokes over the tail (RandomStroke), each sent every step to a second tail that has no
// fingertip of its own. On a step where the sender's patch slipped, its solve had found the patch
// where its anchor was before the slip; the set gave the proxy's point, where the anchor is after
// it, and the receiver found other nodes there. Measured: the share of steps (in contact, force
// under the device's clamp) where the receiver's force on the body differs from the sender's by
// more than 1 % of it.
TEST(TailFriction, APeersSolveOfAContactSetGivesTheForceItsSenderFelt) {
  const double mu = 0.7;
  std::mt19937 rng(11);
  constexpr int kStrokes = 30;
  std::array<Eigen::Vector3d, 5> none;
  none.fill(Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
  int steps = 0, off = 0;
  double worst = 0.0;
  for (int c = 0; c < kStrokes; ++c) {
    const RandomStroke stroke(rng);
    OneFingertipOnTheTail t = stroke.Fingertip(mu);
    SceneModels peer = BuildTail(t.scene);
    const double clamp = 0.99 * t.models.world->config().max_force_N;
    for (int k = 0; k < RandomStroke::kSteps; ++k) {
      stroke.Move(t, k);
      const contact::FingerResult r = t.Step();
      peer.world->Step(1e-3, none, Sent(r));
      if (!r.in_contact || r.f_E_W_N.norm() >= clamp) continue;
      const double e = (peer.world->pose(r.object).linear() * peer.world->remote_forces_O()[0] + r.f_E_W_N).norm() / std::max(r.f_E_W_N.norm(), 0.1);
      ++steps;
      off += e > 0.01 ? 1 : 0;
      worst = std::max(worst, e);
    }
  }
  RecordProperty("steps_compared", std::to_string(steps));
  RecordProperty("steps_over_1_percent", std::to_string(off));
  RecordProperty("largest_difference_over_the_force", std::to_string(worst));
  ASSERT_GT(steps, kStrokes * 1000);
  EXPECT_LE(off, steps / 1000);
}

}  // namespace
}  // namespace handshare::world
