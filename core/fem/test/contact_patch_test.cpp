// A fingertip is a patch: force against depth converges with mesh refinement and matches the
// rigid flat punch (F = 2 a E delta / (1 - nu^2)) and Hertz (F = 4/3 E* sqrt(R) delta^1.5) on
// an elastic half-space, approximated by a large block on graded meshes. A single-node contact,
// in contrast, gets softer with every refinement.

#include <gtest/gtest.h>

#include <cmath>
#include <algorithm>
#include <map>
#include <tuple>
#include <memory>
#include <random>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_patch.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

constexpr double kA = 0.005;      // punch radius [m]
constexpr double kDelta = 1e-4;   // depth [m] (2% of a: small strain)
constexpr Material kMat{1e4, 0.3};
constexpr double kEstar = 1e4 / (1 - 0.3 * 0.3);

// Block [-ext a, ext a]^2 x [-ext a, 0], bottom fixed, spacing a/div within 1.25 a of the
// contact point at the origin, growing by `growth` per cell outside. Compliance only for the
// top nodes within 1.2 a (all a fingertip there can touch).
struct PunchModel {
  double h_m = 0;
  TetMesh mesh;
  std::shared_ptr<Compliance> c;
  std::unique_ptr<ContactPatchFinder> finder;
};

PunchModel MakePunchModel(double ext, double growth, double div) {
  PunchModel m;
  m.h_m = kA / div;
  const auto xy = test::SymmetricGradedAxis(1.25 * kA, m.h_m, ext * kA, growth);
  const auto depth = test::GradedAxis(1.25 * kA, m.h_m, ext * kA, growth);
  std::vector<double> z;
  for (auto it = depth.rbegin(); it != depth.rend(); ++it) z.push_back(-*it);
  m.mesh = MakeGridMesh(xy, xy, z);
  const auto fixed = NodesOnPlane(m.mesh, 2, z.front(), 1e-12);
  ComplianceOptions o;
  for (std::int32_t v : NodesOnPlane(m.mesh, 2, 0.0, 1e-12)) {
    if (m.mesh.positions_m()[v].head<2>().norm() < 1.2 * kA) o.nodes.push_back(v);
  }
  m.c = std::make_shared<Compliance>(Compliance::Precompute(m.mesh, kMat, fixed, o));
  m.finder = std::make_unique<ContactPatchFinder>(m.mesh, ExtractSurface(m.mesh), *m.c);
  return m;
}

const PunchModel& Model(double ext, double growth, double div) {
  static std::map<std::tuple<double, double, double>, PunchModel> cache;
  auto key = std::make_tuple(ext, growth, div);
  auto it = cache.find(key);
  if (it == cache.end()) it = cache.emplace(key, MakePunchModel(ext, growth, div)).first;
  return it->second;
}

struct PunchResult {
  double F_N;        // total normal force
  double a_eff_m;    // radius of the disc with the patch nodes' tributary area
  int nodes;
};

// Frictionless rigid flat punch (the analytic solution assumes no friction), push-only.
PunchResult Punch(const PunchModel& m) {
  std::vector<ContactInput> patch(static_cast<std::size_t>(m.c->num_nodes()));
  const PatchResult r = m.finder->FlatPunch({0, 0, 0}, Eigen::Vector3d::UnitZ(), kA, kDelta,
                                            ContactMode::kNormalOnly, patch);
  EXPECT_FALSE(r.truncated);
  ContactSolver solver(m.c, {.max_contacts = m.c->num_nodes(), .push_only = true});
  EXPECT_EQ(solver.Solve(std::span(patch.data(), static_cast<std::size_t>(r.count))), StepStatus::kOk);
  // The patch nodes of a regular grid each stand for h^2 of surface.
  return {-solver.total_force_N().z(), m.h_m * std::sqrt(r.count / M_PI), r.count};
}

double PunchAnalytic(double a_m) { return 2.0 * a_m * kEstar * kDelta; }

// Refinement on one block (ext 8): the discrete punch force, normalized by the analytic force
// of its effective radius, converges: successive changes shrink (measured 1.074, 1.110, 1.112
// for a/h = 2, 3, 4; 1.118 at a/h = 6).
TEST(ContactPatch, FlatPunchForceConvergesWithRefinement) {
  double prev = 0.0, prev_change = 1e300;
  for (double div : {2.0, 3.0, 4.0}) {
    const PunchResult r = Punch(Model(8, 1.4, div));
    const double ratio = r.F_N / PunchAnalytic(r.a_eff_m);
    if (prev > 0.0) {
      const double change = std::abs(ratio - prev);
      EXPECT_LT(change, prev_change) << "a/h " << div;
      prev_change = change;
    }
    prev = ratio;
  }
  EXPECT_LT(prev_change, 0.01);
}

// Against the half-space solution. Tolerance 8%, and why: the block is finite (rigid base and
// free sides at 24 a; the excess stiffness scales with a / H: +11% at 8 a, +5% at 24 a, so about
// +2% of it remains from the discretization: linear tetrahedra are too stiff and the edge
// singularity of the punch pressure is resolved only to h). Measured: 1.049 (a/h = 3), 1.050
// (a/h = 4), 1.052 (a/h = 6).
TEST(ContactPatch, FlatPunchMatchesHalfSpace) {
  const PunchResult r = Punch(Model(24, 1.5, 4));
  const double ratio = r.F_N / PunchAnalytic(r.a_eff_m);
  RecordProperty("F_over_analytic", test::Sci(ratio));
  EXPECT_GT(ratio, 1.0);  // a finite block is stiffer than the half-space
  EXPECT_LT(ratio, 1.08);
  // The nominal radius, too: the node disc is within one spacing of it.
  EXPECT_NEAR(r.a_eff_m, kA, Model(24, 1.5, 4).h_m);
}

// Hertz: a sphere R = 4 a pressed so that the Hertz contact radius sqrt(R delta) is 0.75 a.
// The patch covers the geometric overlap sqrt(2 R delta); push-only releases the rim where the
// surface would pull, leaving about the Hertz contact radius. Tolerance 15%: the block excess
// (+5%, as for the punch) plus the contact edge resolved to h (converging from above: measured
// 1.104, 1.075, 1.064 for a/h = 3, 4, 6 at 24 a).
TEST(ContactPatch, SphereMatchesHertzWithPushOnly) {
  const PunchModel& m = Model(24, 1.5, 4);
  const double R = 4 * kA;
  const double a_hertz = 0.75 * kA;
  const double depth = a_hertz * a_hertz / R;
  std::vector<ContactInput> patch(static_cast<std::size_t>(m.c->num_nodes()));
  const PatchResult r = m.finder->Sphere({0, 0, 0}, Eigen::Vector3d::UnitZ(), R, depth,
                                         ContactMode::kNormalOnly, patch);
  EXPECT_NEAR(r.contact_radius_m, std::sqrt(2 * R * depth), 1e-15);
  ContactSolver solver(m.c, {.max_contacts = m.c->num_nodes(), .push_only = true});
  ASSERT_EQ(solver.Solve(std::span(patch.data(), static_cast<std::size_t>(r.count))), StepStatus::kOk);
  const double F = -solver.total_force_N().z();
  const double F_hertz = 4.0 / 3.0 * kEstar * std::sqrt(R) * std::pow(depth, 1.5);
  RecordProperty("F_over_hertz", test::Sci(F / F_hertz));
  EXPECT_GT(F / F_hertz, 1.0);
  EXPECT_LT(F / F_hertz, 1.15);
  // The held region is the Hertz contact disc, to within one spacing.
  double r_held = 0.0, r_released = 1e300;
  for (std::int32_t i = 0; i < r.count; ++i) {
    const double rr = m.mesh.positions_m()[patch[i].node].head<2>().norm();
    if (solver.states()[i] == ContactState::kActive) {
      r_held = std::max(r_held, rr);
    } else {
      r_released = std::min(r_released, rr);
    }
  }
  EXPECT_LT(r_held, a_hertz + m.h_m);
  EXPECT_GT(r_released, a_hertz - m.h_m);
  // Without push-only the rim pulls the surface up: the force is too small.
  ContactSolver sticky(m.c, {.max_contacts = m.c->num_nodes()});
  ASSERT_EQ(sticky.Solve(std::span(patch.data(), static_cast<std::size_t>(r.count))), StepStatus::kOk);
  EXPECT_LT(-sticky.total_force_N().z(), F);
}

// Force against depth follows Hertz's delta^1.5 as the patch grows with depth: doubling the depth
// (contact radius 0.53 a -> 0.75 a) multiplies the force by 2^1.5 = 2.83. Tolerance 10%: the
// smaller contact disc is resolved by only ~2 spacings.
TEST(ContactPatch, SphereForceGrowsLikeDepthToThreeHalves) {
  const PunchModel& m = Model(24, 1.5, 4);
  const double R = 4 * kA;
  const double depth = 0.75 * kA * 0.75 * kA / R;
  auto force = [&](double d) {
    std::vector<ContactInput> patch(static_cast<std::size_t>(m.c->num_nodes()));
    const PatchResult r = m.finder->Sphere({0, 0, 0}, Eigen::Vector3d::UnitZ(), R, d,
                                           ContactMode::kNormalOnly, patch);
    ContactSolver solver(m.c, {.max_contacts = m.c->num_nodes(), .push_only = true});
    EXPECT_EQ(solver.Solve(std::span(patch.data(), static_cast<std::size_t>(r.count))), StepStatus::kOk);
    return -solver.total_force_N().z();
  };
  const double ratio = force(depth) / force(depth / 2);
  RecordProperty("force_ratio_for_double_depth", test::Sci(ratio));
  EXPECT_NEAR(ratio, std::pow(2.0, 1.5), 0.1 * std::pow(2.0, 1.5));
}

// The pitfall the patch avoids: a single touched node's stiffness 1 / (n^T C_kk n) is about
// 1.1 E h and goes to zero with refinement (ratio of the two meshes ~ h4 / h3 = 0.75).
TEST(ContactPatch, SingleNodeStiffnessVanishesWithRefinement) {
  auto stiffness = [](const PunchModel& m) {
    const std::int32_t slot = m.c->SlotOf(*std::min_element(
        m.c->nodes().begin(), m.c->nodes().end(), [&](std::int32_t a, std::int32_t b) {
          return m.mesh.positions_m()[a].norm() < m.mesh.positions_m()[b].norm();
        }));
    return 1.0 / m.c->Block(slot, slot)(2, 2);
  };
  const double k3 = stiffness(Model(8, 1.4, 3));
  const double k4 = stiffness(Model(8, 1.4, 4));
  EXPECT_NEAR(k4 / k3, 0.75, 0.08);
  EXPECT_NEAR(k4 / (kMat.E_Pa * kA / 4), 1.1, 0.3);  // "about 1.1 E h" (FEM-NOTES)
}

TEST(ContactPatch, TruncatesToCapacityKeepingTheClosestNodes) {
  const PunchModel& m = Model(8, 1.4, 3);
  std::vector<ContactInput> few(5);
  const PatchResult r = m.finder->FlatPunch({0, 0, 0}, Eigen::Vector3d::UnitZ(), kA, kDelta,
                                            ContactMode::kFull3d, few);
  EXPECT_TRUE(r.truncated);
  EXPECT_EQ(r.count, 5);
  // On this grid the centre node and its 4 neighbours are the 5 closest.
  for (const auto& c : few) EXPECT_LT(m.mesh.positions_m()[c.node].head<2>().norm(), m.h_m * 1.01);
  // Nothing under a fingertip that misses the object, or with no depth.
  std::vector<ContactInput> out(10);
  EXPECT_EQ(m.finder->FlatPunch({1, 1, 1}, Eigen::Vector3d::UnitZ(), kA, kDelta, ContactMode::kFull3d, out).count, 0);
  EXPECT_EQ(m.finder->Sphere({0, 0, 0}, Eigen::Vector3d::UnitZ(), 0.01, 0.0, ContactMode::kFull3d, out).count, 0);
}

// The patch holds every node of the footprint, wherever the fingertip is and whichever way its
// normal points: the nodes the finder returns are exactly those a scan of all compliance nodes
// takes by the same rule (within the contact radius a of the contact point across the normal,
// within a of its tangent plane along it -- the slab is a where a exceeds the grid's cell, as
// here -- on the side of the surface facing the fingertip, pressed). Guards the cells the finder
// visits (a box about the footprint), which a narrower box would cut.
TEST(ContactPatch, FindsEveryNodeOfTheFootprintWhateverTheNormal) {
  const TetMesh mesh = MakeBoxMesh({0.04, 0.04, 0.04}, {8, 8, 8});
  const Surface surface = ExtractSurface(mesh);
  const auto fixed = NodesOnPlane(mesh, 2, 0.0, 1e-12);
  const auto c = std::make_shared<Compliance>(Compliance::Precompute(mesh, kMat, fixed, {}));
  const ContactPatchFinder finder(mesh, surface, *c);
  const auto& x = mesh.positions_m();
  double max_edge = 0.0;
  for (const Triangle& t : surface.triangles) {
    for (int e = 0; e < 3; ++e) max_edge = std::max(max_edge, (x[t[(e + 1) % 3]] - x[t[e]]).norm());
  }
  std::vector<Eigen::Vector3d> normal_of(x.size(), Eigen::Vector3d::Zero());
  for (std::size_t i = 0; i < surface.nodes.size(); ++i) normal_of[surface.nodes[i]] = surface.normals[i];
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  std::vector<ContactInput> out(static_cast<std::size_t>(c->num_nodes()));
  int nonempty = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const Eigen::Vector3d p = Eigen::Vector3d(0.02, 0.02, 0.02) + 0.028 * Eigen::Vector3d(U(rng), U(rng), U(rng));
    Eigen::Vector3d n(U(rng), U(rng), U(rng));
    if (n.norm() < 0.1) continue;
    n.normalize();
    const double R = 0.05;
    const double a = (2.2 + 1.5 * (U(rng) + 1.0)) * max_edge;  // above the cell (twice the mean edge)
    const double depth = a * a / (2.0 * R);
    const PatchResult r = finder.Sphere(p, n, R, depth, ContactMode::kNormalOnly, out);
    ASSERT_FALSE(r.truncated);
    std::vector<std::int32_t> found;
    for (std::int32_t k = 0; k < r.count; ++k) {
      found.push_back(out[static_cast<std::size_t>(k)].node);
      const Eigen::Vector3d d = x[out[static_cast<std::size_t>(k)].node] - p;
      const double rk = (d - d.dot(n) * n).norm();
      EXPECT_NEAR((out[static_cast<std::size_t>(k)].u_m + (depth - rk * rk / (2.0 * R)) * n).norm(), 0.0, 1e-15);
    }
    std::vector<std::int32_t> expected;
    for (const std::int32_t node : c->nodes()) {
      const Eigen::Vector3d d = x[node] - p;
      const double h = d.dot(n);
      const double rr = (d - h * n).norm();
      if (std::abs(h) <= a && rr < a && normal_of[node].dot(n) >= 0.3 && depth - rr * rr / (2.0 * R) > 0.0) {
        expected.push_back(node);
      }
    }
    std::sort(found.begin(), found.end());
    ASSERT_EQ(found, expected) << "trial " << trial << " at " << p.transpose() << ", n " << n.transpose();
    nonempty += expected.empty() ? 0 : 1;
  }
  EXPECT_GT(nonempty, 100);  // most trials touch the block
}

}  // namespace
}  // namespace handshare::fem
