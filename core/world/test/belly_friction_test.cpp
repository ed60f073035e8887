// Fingertips pressed into the Daphnia's beating belly (the microscopic_belly scene's mesh,
// prepared as every node prepares it) and drawn over it at random. The belly's surface has 1-4
// nodes under a fingertip; there a friction patch that slips buzzes as a node at its rim comes
// and goes (docs/fem.md, "Limits"), so the scene ships the belly frictionless. What a user would
// feel is measured per stroke: the largest 1 ms change of the force over the normal force (a
// coarse surface steps as nodes come and go) and the largest second difference over it (a buzz:
// the force stepping one way and back).
// The belly beats, and each stroke is measured on a fresh copy of it: 4.5 s for both sets.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "handshare/scene/scene.hpp"
#include "handshare/world/scene_models.hpp"
#include "test_models.hpp"

namespace handshare::world {
namespace {

// The belly scene reduced to its belly; mu < 0 keeps the scene's own coefficients.
scene::Scene BellyScene(double mu) {
  scene::Scene s =
      scene::LoadScene(std::filesystem::path(HANDSHARE_SOURCE_ASSETS) / "scenes" / "microscopic_belly.json");
  std::erase_if(s.objects, [](const scene::SceneObject& o) { return o.id != "daphnia_belly"; });
  if (s.objects.size() != 1 || !s.objects[0].beat.active()) {
    throw std::runtime_error("microscopic_belly.json has no single beating daphnia_belly");
  }
  if (mu >= 0.0) {
    s.objects[0].deformable.mu_static = mu;
    s.objects[0].deformable.mu_kinetic = mu;
  }
  return s;
}

SceneModels BuildBelly(const scene::Scene& s) { return test::BuildCached(s, "handshare_belly_friction_cache"); }

struct Strokes {
  std::vector<double> largest_step;        // per stroke, over the normal force
  std::vector<double> largest_second_diff;  // per stroke, over the normal force
  int steps_in_contact = 0;
};

// Thirty strokes, each on a fresh belly: a fingertip 6 mm off a random surface node on the
// visitor's side (outward normal within 37 degrees of -y in W, below the held back), pressed
// 8-11 mm along the node's normal in 0.2 s (2-5 mm into the rest surface), held, drawn along a
// random tangent at 0.3-20 mm/s for 0.8 s, held again; the belly beats throughout from a
// random phase. Steps count from 5 ms after the press ends (its end is no buzz), once the
// fingertip has touched for three steps running.
Strokes RandomStrokes(const scene::Scene& s) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  const SceneModels probe = BuildBelly(s);
  const PreparedDeformable& belly = probe.deformables[0];
  const Eigen::Isometry3d X_WO = s.objects[0].X_WO();
  std::vector<std::size_t> facing;
  for (std::size_t i = 0; i < belly.surface->nodes.size(); ++i) {
    const Eigen::Vector3d n_W = X_WO.linear() * belly.surface->normals[i];
    const Eigen::Vector3d& p = belly.mesh->positions_m()[static_cast<std::size_t>(belly.surface->nodes[i])];
    if (n_W.y() < -0.8 && p.z() < 0.0) facing.push_back(i);
  }
  if (facing.size() < 10) throw std::runtime_error("the belly has too few nodes facing the visitor");
  const double R = probe.world->config().fingertip_radius_m;
  Strokes out;
  for (int c = 0; c < 30; ++c) {
    SceneModels w = BuildBelly(s);
    const std::size_t i = facing[static_cast<std::size_t>(uniform(rng) * static_cast<double>(facing.size()))];
    const Eigen::Vector3d n_W = X_WO.linear() * belly.surface->normals[i];
    const Eigen::Vector3d p_W = X_WO * belly.mesh->positions_m()[static_cast<std::size_t>(belly.surface->nodes[i])];
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
    int touching = 0;
    double step = 0.0, second = 0.0;
    for (int k = 0; k < 1400; ++k) {
      if (k < 200) {
        tip -= (0.006 + depth) / 200 * n_W;
      } else if (k >= 300 && k < 1100) {
        tip += speed * along;
      }
      tips[1] = tip;
      w.world->SetModeScale(0, s.objects[0].beat.Scale(phase_s + 1e-3 * k));
      w.world->Step(1e-3, tips);
      const contact::FingerResult& r = w.world->fingers()[1];
      touching = r.in_contact ? touching + 1 : 0;
      if (k >= 205 && touching >= 3) {
        ++out.steps_in_contact;
        const double fn = std::max(r.f_E_W_N.dot(r.n_W), 0.3);
        step = std::max(step, (r.f_E_W_N - f1).norm() / fn);
        second = std::max(second, (r.f_E_W_N - 2 * f1 + f2).norm() / fn);
      }
      f2 = f1;
      f1 = r.f_E_W_N;
    }
    out.largest_step.push_back(step);
    out.largest_second_diff.push_back(second);
  }
  return out;
}

double Median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}
long Over(const std::vector<double>& v, double bound) {
  return static_cast<long>(std::count_if(v.begin(), v.end(), [&](double x) { return x > bound; }));
}
double Largest(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }

// The belly as the scene ships it (frictionless) steps as nodes come and go (its coarse surface)
// but does not buzz: no stroke's second difference reaches 5 % of its normal force (measured:
// median 0.14 %, largest 4.1 %). The same strokes with friction at 0.4 are recorded, not held to
// it: the median stroke buzzes by 8.3 % of F_n, 16 of 30 strokes over 5 %, up to 81 %
// (2026-11-28; docs/fem.md, "Limits"). Friction on the belly in the scene fails this test; it
// goes in when a slipping patch on a coarse surface stops buzzing.
TEST(BellyFriction, TheShippedBeatingBellyDoesNotBuzzUnderAStroke) {
  const scene::Scene as_shipped = BellyScene(-1.0);
  const Strokes shipped = RandomStrokes(as_shipped);
  RecordProperty("shipped_mu", std::to_string(as_shipped.objects[0].deformable.mu_static));
  RecordProperty("median_largest_step_over_normal_force", std::to_string(Median(shipped.largest_step)));
  RecordProperty("median_largest_second_difference", std::to_string(Median(shipped.largest_second_diff)));
  RecordProperty("strokes_buzzing_over_5_percent", std::to_string(Over(shipped.largest_second_diff, 0.05)) + " of 30");
  RecordProperty("largest_second_difference", std::to_string(Largest(shipped.largest_second_diff)));
  const Strokes friction = RandomStrokes(BellyScene(0.4));
  RecordProperty("at_mu_0_4_median_largest_step", std::to_string(Median(friction.largest_step)));
  RecordProperty("at_mu_0_4_median_largest_second_difference", std::to_string(Median(friction.largest_second_diff)));
  RecordProperty("at_mu_0_4_strokes_buzzing_over_5_percent",
                 std::to_string(Over(friction.largest_second_diff, 0.05)) + " of 30");
  RecordProperty("at_mu_0_4_largest_second_difference", std::to_string(Largest(friction.largest_second_diff)));
  // Every stroke pressed the belly for most of its 1.2 s after the press.
  ASSERT_GT(shipped.steps_in_contact, 30 * 900);
  ASSERT_GT(friction.steps_in_contact, 30 * 900);
  EXPECT_EQ(Over(shipped.largest_second_diff, 0.05), 0);
}

}  // namespace
}  // namespace handshare::world
