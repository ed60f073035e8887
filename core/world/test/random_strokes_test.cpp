// Fingertips pressed into the Daphnia's beating belly and horn and the triceratops' tail (each
// scene's mesh, prepared as every node prepares it) and drawn over them at random. What a user
// would feel is measured per stroke: the largest 1 ms change of the force over the normal force
// (a coarse surface steps as nodes come and go), the largest second difference over it (a buzz:
// the force stepping one way and back) and how many steps buzz so (a click or a hum).
// The belly has 1-4 nodes under a fingertip, the tail 2-12; both ship with friction, and the
// same strokes are held to the same bounds on both. The horn (a bending spine, 1-2 nodes under a
// fingertip) still ships frictionless.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/scene/scene.hpp"
#include "handshare/world/scene_models.hpp"
#include "test_models.hpp"

namespace handshare::world {
namespace {

// A scene reduced to one of its deformables; mu < 0 keeps the scene's own coefficients.
scene::Scene OneBody(const char* scene_file, const char* id, double mu) {
  scene::Scene s = test::OneDeformable(scene_file, id);
  if (mu >= 0.0) {
    s.objects[0].deformable.mu_static = mu;
    s.objects[0].deformable.mu_kinetic = mu;
  }
  return s;
}

scene::Scene Belly(double mu = -1.0) { return OneBody("microscopic_belly.json", "daphnia_belly", mu); }
scene::Scene Horn(double mu = -1.0) { return OneBody("microscopic_horn.json", "daphnia_horn", mu); }
scene::Scene Tail(double mu = -1.0) { return OneBody("dinosaur.json", "triceratops_tail", mu); }

// Where a stroke may start: a surface node's outward normal in W and its rest position in O.
using Facing = std::function<bool(const Eigen::Vector3d& n_W, const Eigen::Vector3d& p_O)>;
// The visitor's side of the belly (-y in W), below its held back.
bool BellySide(const Eigen::Vector3d& n_W, const Eigen::Vector3d& p_O) { return n_W.y() < -0.8 && p_O.z() < 0.0; }
// The visitor's side of the horn, past the band by its root.
bool HornSide(const Eigen::Vector3d& n_W, const Eigen::Vector3d& p_O) { return n_W.y() < -0.8 && p_O.x() < -0.02; }
// The tail's top, past its attached base.
bool TailTop(const Eigen::Vector3d& n_W, const Eigen::Vector3d& p_O) { return n_W.z() > 0.8 && p_O.x() < -0.02; }

struct Strokes {
  std::vector<double> largest_step;         // per stroke, over the normal force
  std::vector<double> largest_second_diff;  // per stroke, over the normal force
  std::vector<int> buzzing_steps;           // per stroke: second difference over 5 % of F_n
  int steps_in_contact = 0;
};

// Thirty strokes, each on a fresh body: a fingertip 6 mm off a random surface node where
// `facing` allows, pressed 8-11 mm along the node's normal in 0.2 s (2-5 mm into the rest
// surface), held, drawn along a random tangent at 0.3-20 mm/s for 0.8 s, held again; a beating
// body beats throughout from a random phase. Steps count from 5 ms after the press ends (its
// end is no buzz), once the fingertip has touched for three steps running.
Strokes RandomStrokes(const scene::Scene& s, const Facing& facing) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const SceneModels probe = test::BuildCached(s, "handshare_random_strokes_cache");
  const PreparedDeformable& body = probe.deformables[0];
  const Eigen::Isometry3d X_WO = s.objects[0].X_WO();
  const bool beats = s.objects[0].beat.active();
  std::vector<std::size_t> starts;
  for (std::size_t i = 0; i < body.surface->nodes.size(); ++i) {
    const Eigen::Vector3d n_W = X_WO.linear() * body.surface->normals[i];
    if (facing(n_W, body.mesh->positions_m()[static_cast<std::size_t>(body.surface->nodes[i])])) starts.push_back(i);
  }
  if (starts.size() < 10) throw std::runtime_error("too few surface nodes where the strokes start");
  const double R = probe.world->config().fingertip_radius_m;
  Strokes out;
  for (int c = 0; c < 30; ++c) {
    SceneModels w = test::BuildCached(s, "handshare_random_strokes_cache");
    const std::size_t i = starts[static_cast<std::size_t>(uniform(rng) * static_cast<double>(starts.size()))];
    const Eigen::Vector3d n_W = X_WO.linear() * body.surface->normals[i];
    const Eigen::Vector3d p_W = X_WO * body.mesh->positions_m()[static_cast<std::size_t>(body.surface->nodes[i])];
    const double depth = 0.002 + 0.003 * uniform(rng);
    const double angle = 2 * M_PI * uniform(rng);
    const double speed = std::pow(10.0, -0.5 + 1.8 * uniform(rng)) * 1e-6;  // per step
    const double phase_s = 1.2 * uniform(rng);
    const Eigen::Vector3d t1 = n_W.unitOrthogonal(), t2 = n_W.cross(t1);
    const Eigen::Vector3d along = std::cos(angle) * t1 + std::sin(angle) * t2;
    std::array<Eigen::Vector3d, 5> tips;
    tips.fill(Eigen::Vector3d(5, 5, 5));
    Eigen::Vector3d tip = p_W + (R + 0.006) * n_W;
    Eigen::Vector3d f1 = Eigen::Vector3d::Zero(), f2 = Eigen::Vector3d::Zero();  // the last two steps'
    int touching = 0, buzzing = 0;
    double step = 0.0, second = 0.0;
    for (int k = 0; k < 1400; ++k) {
      if (k < 200) {
        tip -= (0.006 + depth) / 200 * n_W;
      } else if (k >= 300 && k < 1100) {
        tip += speed * along;
      }
      tips[1] = tip;
      if (beats) w.world->SetModeScale(0, s.objects[0].beat.Scale(phase_s + 1e-3 * k));
      w.world->Step(1e-3, tips);
      const contact::FingerResult& r = w.world->fingers()[1];
      touching = r.in_contact ? touching + 1 : 0;
      if (k >= 205 && touching >= 3) {
        ++out.steps_in_contact;
        const double fn = std::max(r.f_E_W_N.dot(r.n_W), 0.3);
        const double d2 = (r.f_E_W_N - 2 * f1 + f2).norm() / fn;
        step = std::max(step, (r.f_E_W_N - f1).norm() / fn);
        second = std::max(second, d2);
        buzzing += d2 > 0.05 ? 1 : 0;
      }
      f2 = f1;
      f1 = r.f_E_W_N;
    }
    out.largest_step.push_back(step);
    out.largest_second_diff.push_back(second);
    out.buzzing_steps.push_back(buzzing);
  }
  return out;
}

template <class T>
T Median(std::vector<T> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
long Over(const std::vector<double>& v, double bound) {
  return static_cast<long>(std::count_if(v.begin(), v.end(), [&](double x) { return x > bound; }));
}
template <class T>
T Largest(const std::vector<T>& v) {
  return *std::max_element(v.begin(), v.end());
}
int Total(const std::vector<int>& v) {
  int t = 0;
  for (int x : v) t += x;
  return t;
}

void Record(const std::string& name, const Strokes& s) {
  ::testing::Test::RecordProperty(name + "_median_largest_step", std::to_string(Median(s.largest_step)));
  ::testing::Test::RecordProperty(name + "_median_largest_second_difference", std::to_string(Median(s.largest_second_diff)));
  ::testing::Test::RecordProperty(name + "_strokes_buzzing_over_5_percent", std::to_string(Over(s.largest_second_diff, 0.05)) + " of 30");
  ::testing::Test::RecordProperty(name + "_largest_second_difference", std::to_string(Largest(s.largest_second_diff)));
  ::testing::Test::RecordProperty(name + "_buzzing_steps", std::to_string(Total(s.buzzing_steps)) + " of " +
                                                               std::to_string(s.steps_in_contact));
  ::testing::Test::RecordProperty(name + "_most_buzzing_steps_in_a_stroke", std::to_string(Largest(s.buzzing_steps)));
}

// What the same strokes are held to on each body that ships with friction. Before a slip kept
// the way it started and its anchor followed the solved slide a quarter of the way (haptic
// world, 2026-11-28), the belly at 0.4 buzzed in 407 of 35,638 steps (the median stroke's
// largest second difference 8.3 % of F_n, one stroke humming for 117 steps) and the tail as
// shipped in 144 of 35,850 (3.6 %, 31): both fail. Measured after: belly 40 steps (1.2 %, 16),
// tail 46 (0.8 %, 17).
void ExpectGlides(const std::string& name, const Strokes& s) {
  Record(name, s);
  ASSERT_GT(s.steps_in_contact, 30 * 900) << name;  // every stroke pressed for most of its 1.2 s
  EXPECT_LT(Median(s.largest_second_diff), 0.02) << name;
  EXPECT_LE(Total(s.buzzing_steps), s.steps_in_contact / 500) << name;
  EXPECT_LE(Largest(s.buzzing_steps), 25) << name;
}

// The belly ships with friction (0.4), at no more buzz than the tail's (0.7) under the same
// strokes. A click remains: a patch whose every held node pulls along the surface holds its
// normal only, and under a fingertip at rest drops its friction for a step (the tail's largest
// second difference, 0.89 F_n; 1.48 before such nodes got kinetic friction under a moving
// fingertip; docs/fem.md, "Limits"); it is recorded, not bounded.
TEST(DaphniaFriction, TheBellyGlidesUnderRandomStrokesAsTheTailDoes) {
  const scene::Scene belly = Belly();
  ASSERT_GT(belly.objects[0].deformable.mu_kinetic, 0.0) << "the belly ships with friction";
  RecordProperty("belly_mu", std::to_string(belly.objects[0].deformable.mu_kinetic));
  ExpectGlides("belly", RandomStrokes(belly, BellySide));
  ExpectGlides("tail", RandomStrokes(Tail(), TailTop));
  // Frictionless, the belly steps as nodes come and go but does not buzz (recorded).
  Record("belly_frictionless", RandomStrokes(Belly(0.0), BellySide));
}

// The horn is a stiff spine (200 MPa) that bends rather than dents: a fingertip on it holds one
// or two nodes, and a held node pulls when held along the surface. Until 2026-12-02 such a node
// kept its normal constraint only and no friction, and the patch toggled between no friction and
// its whole cone: at 0.4 the horn buzzed in 28 of 30 strokes (1,131 of 33,239 steps, one stroke
// for 201) against 12 steps frictionless. A patch that holds no node in 3-D now gives those nodes
// kinetic friction (docs/fem.md, "Kinetic friction on nodes held along their normal"): 205 steps,
// one stroke for 51, the largest second difference 5.3 F_n (40 before). The rest is a fingertip
// held still on the beating horn (before and after each stroke), whose patch has no motion to
// slide along and toggles as before; so the horn still ships frictionless. The bound of 400 steps
// fails without kinetic friction (1,131); the second check fails when the scene gives the horn
// friction while it still buzzes more than the belly and the tail may.
TEST(DaphniaFriction, TheHornShipsFrictionlessForFrictionMakesItBuzz) {
  const scene::Scene horn = Horn();
  EXPECT_EQ(horn.objects[0].deformable.mu_static, 0.0);
  Record("horn_frictionless", RandomStrokes(horn, HornSide));
  const Strokes at_0_4 = RandomStrokes(Horn(0.4), HornSide);
  Record("horn_at_mu_0_4", at_0_4);
  EXPECT_LE(Total(at_0_4.buzzing_steps), 400);
  EXPECT_GT(Total(at_0_4.buzzing_steps), at_0_4.steps_in_contact / 500);
}

// Strokes along the spine: a fingertip pressed 3 mm into the side of the horn 30, 50, 70 and
// 90 mm out from its root, drawn along the spine toward its tip and toward its root at 10 mm/s
// (at the same friction as the belly, 0.4; the horn ships frictionless, above). Once the slip is
// steady (from 0.2 s into the stroke), the drag against the motion is mu_k times the push in
// every step, within 5 % (measured: 0.4 % at most, the mean 0.3986-0.3999 F_n); the force sideways
// stays under 10 % of mu_k times the push (measured: 9.2 % at 90 mm, where the spine tapers and
// its surface turns along the stroke). Without kinetic friction on nodes held along their normal
// 5 of the 8 strokes (50 mm toward the tip, 70 and 90 mm both ways) dragged nothing for some
// steps, the one 70 mm out toward the tip nothing at all.
TEST(DaphniaFriction, AStrokeAlongTheSpineDragsWithMuTimesItsPush) {
  const scene::Scene horn = Horn(0.4);
  const double mu = horn.objects[0].deformable.mu_kinetic;
  const Eigen::Isometry3d X_WO = horn.objects[0].X_WO();
  for (const double x_O : {-0.03, -0.05, -0.07, -0.09}) {
    for (const double toward : {-1.0, 1.0}) {  // -1: toward the tip (-x in O)
      SceneModels w = test::BuildCached(horn, "handshare_random_strokes_cache");
      const PreparedDeformable& body = w.deformables[0];
      // The side node nearest x_O along the spine, on its midline.
      std::size_t start = body.surface->nodes.size();
      double best = 1e9;
      for (std::size_t i = 0; i < body.surface->nodes.size(); ++i) {
        const Eigen::Vector3d n_W = X_WO.linear() * body.surface->normals[i];
        const Eigen::Vector3d& p_O = body.mesh->positions_m()[static_cast<std::size_t>(body.surface->nodes[i])];
        if (!HornSide(n_W, p_O)) continue;
        const double d = std::abs(p_O.x() - x_O) + std::abs(p_O.z());
        if (d < best) {
          best = d;
          start = i;
        }
      }
      ASSERT_LT(start, body.surface->nodes.size());
      const Eigen::Vector3d n_W = X_WO.linear() * body.surface->normals[start];
      const Eigen::Vector3d p_W = X_WO * body.mesh->positions_m()[static_cast<std::size_t>(body.surface->nodes[start])];
      const Eigen::Vector3d x_W = toward * (X_WO.linear() * Eigen::Vector3d::UnitX());
      const Eigen::Vector3d along = (x_W - x_W.dot(n_W) * n_W).normalized();
      const double R = w.world->config().fingertip_radius_m;
      std::array<Eigen::Vector3d, 5> tips;
      tips.fill(Eigen::Vector3d(5, 5, 5));
      Eigen::Vector3d tip = p_W + (R + 0.006) * n_W;
      double worst_drag = 0.0, worst_side = 0.0, sum_ratio = 0.0;
      int steps = 0;
      for (int k = 0; k < 1100; ++k) {
        if (k < 200) {
          tip -= (0.006 + 0.003) / 200 * n_W;
        } else if (k >= 300) {
          tip += 10e-6 * along;
        }
        tips[1] = tip;
        w.world->Step(1e-3, tips);
        const contact::FingerResult& r = w.world->fingers()[1];
        if (k < 500) continue;
        ASSERT_TRUE(r.in_contact) << x_O << " " << toward << " step " << k;
        const double push = r.f_E_W_N.dot(r.n_W);
        ASSERT_GT(push, 0.1) << x_O << " " << toward << " step " << k;
        const Eigen::Vector3d f_t = r.f_E_W_N - push * r.n_W;
        const double drag = -f_t.dot(along);  // the fingertip is held back
        const Eigen::Vector3d side = f_t + drag * along;
        worst_drag = std::max(worst_drag, std::abs(drag / (mu * push) - 1.0));
        worst_side = std::max(worst_side, side.norm() / (mu * push));
        sum_ratio += drag / push;
        ++steps;
      }
      const std::string name = "at_" + std::to_string(static_cast<int>(-1000 * x_O)) + "_mm_" + (toward < 0 ? "tipward" : "rootward");
      RecordProperty(name + "_mean_drag_over_push", std::to_string(sum_ratio / steps));
      RecordProperty(name + "_worst_drag_error", std::to_string(worst_drag));
      EXPECT_LT(worst_drag, 0.05) << name << ": mean drag / push " << sum_ratio / steps << " against mu " << mu;
      EXPECT_LT(worst_side, 0.10) << name;
    }
  }
}

}  // namespace
}  // namespace handshare::world
