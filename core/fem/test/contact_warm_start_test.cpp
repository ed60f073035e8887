// The push-only frictionless path of ContactSolver keeps state between Solve() calls: the held
// set of the previous step (warm start) and a table of the compliance blocks of nodes touched
// in consecutive steps. Neither may change the answer: the LCP has exactly one solution, and
// the table holds the very blocks the compliance gives. Checked here on five sliding fingertip
// patches (nodes entering and leaving every few steps, fingers lifting off, a NaN step and a
// sticking step in between) against a fresh solver per step and against the contact conditions
// themselves (displacements through Displacements(), an independent path over the blocks).
// With friction patches it keeps the factor of its last held set, resumed after the rows that
// stayed: checked against a fresh solver per step too.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_patch.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

constexpr Material kMat{1e4, 0.3};
constexpr double kR = 0.008;  // fingertip radius [m]

struct Plate {
  test::Block block;
  std::shared_ptr<const Compliance> c;
  std::unique_ptr<ContactPatchFinder> finder;
};

// 6 x 6 x 2 cm block, bottom fixed, 3.75 mm spacing; compliance for the top face only.
const Plate& TopPlate() {
  static const Plate p = [] {
    Plate q{test::MakeFixedBottomBox({0.06, 0.06, 0.02}, {16, 16, 4}), nullptr, nullptr};
    ComplianceOptions o;
    o.nodes = NodesOnPlane(q.block.mesh, 2, 0.02, 1e-12);
    q.c = std::make_shared<Compliance>(Compliance::Precompute(q.block.mesh, kMat, q.block.fixed, o));
    q.finder = std::make_unique<ContactPatchFinder>(q.block.mesh, ExtractSurface(q.block.mesh), *q.c);
    return q;
  }();
  return p;
}

// Five fingertips circling on the top face at 0.1-0.2 mm per step, pressing -0.3..2 mm (a
// finger above the surface has no patch).
std::vector<ContactInput> Patches(const Plate& p, int step) {
  std::vector<ContactInput> all;
  std::vector<ContactInput> buf(64);
  for (int f = 0; f < 5; ++f) {
    const double t = 1e-3 * step;
    const double ang = (4.0 + f) * t + 1.2566 * f;
    const double rad = 0.008 + 0.003 * f;
    const Eigen::Vector3d c(0.03 + rad * std::cos(ang), 0.03 + rad * std::sin(ang), 0.02);
    const double depth = 0.00085 + 0.00115 * std::sin(20.0 * t + f);
    const PatchResult r = p.finder->Sphere(c, Eigen::Vector3d::UnitZ(), kR, depth,
                                           ContactMode::kNormalOnly, buf);
    all.insert(all.end(), buf.begin(), buf.begin() + r.count);
  }
  return all;
}

double MaxForce(const ContactSolver& s) {
  double m = 0.0;
  for (const auto& f : s.forces_N()) m = std::max(m, f.norm());
  return m;
}

// The persistent solver against a new solver per step (cold start, every block read from the
// compliance). Tolerance 1e-9 of the largest force: both factor the same held rows in the same
// order, so only the round-off of n_i^T C_ij n_j against n_j^T C_ji n_i (~1e-16) and a node
// whose force is within the pivoting tolerance (1e-9 relative) of zero can separate them.
TEST(ContactWarmStart, SlidingPatchesMatchAFreshSolvePerStep) {
  const Plate& p = TopPlate();
  const ContactSolverOptions opt{.max_contacts = 160, .push_only = true};
  ContactSolver warm(p.c, opt);
  int steps_with_contacts = 0, warm_iterations = 0, cold_iterations = 0, released = 0;
  for (int step = 0; step < 400; ++step) {
    std::vector<ContactInput> in = Patches(p, step);
    if (step == 150) {  // a NaN sample: rejected, and the table must forget this step
      in.front().u_m.x() = std::numeric_limits<double>::quiet_NaN();
      EXPECT_EQ(warm.Solve(in), StepStatus::kInvalidInput);
      continue;
    }
    if (step == 250 && !in.empty()) in.front().mode = ContactMode::kFull3d;  // the general path
    ContactSolver cold(p.c, opt);
    const StepStatus sw = warm.Solve(in);
    const StepStatus sc = cold.Solve(in);
    ASSERT_EQ(sw, sc) << "step " << step;
    ASSERT_EQ(sw, StepStatus::kOk) << "step " << step;
    if (in.empty()) continue;
    ++steps_with_contacts;
    warm_iterations += warm.active_set_iterations();
    cold_iterations += cold.active_set_iterations();
    const double scale = std::max(MaxForce(cold), 1e-12);
    for (std::size_t i = 0; i < in.size(); ++i) {
      const double diff = (warm.forces_N()[i] - cold.forces_N()[i]).norm();
      ASSERT_LE(diff, 1e-9 * scale) << "step " << step << " contact " << i;
      if (warm.states()[i] != cold.states()[i]) {
        EXPECT_LE(cold.forces_N()[i].norm(), 1e-9 * scale) << "step " << step;
      }
      released += cold.states()[i] == ContactState::kReleased ? 1 : 0;
    }
  }
  EXPECT_GT(steps_with_contacts, 300);
  EXPECT_GT(released, 100);  // the rims were released: the pivoting had work to do
  // The warm start is why the state is kept: it needs fewer active-set changes.
  RecordProperty("warm_iterations", warm_iterations);
  RecordProperty("cold_iterations", cold_iterations);
  EXPECT_LT(warm_iterations, cold_iterations);
}

// The contact conditions, independent of how the solver got there: held nodes sit at their
// imposed normal displacement and push; released nodes carry no force and the surface under
// them stays below the fingertip. Displacements() sums C.Block(n, k) f_k over the held nodes,
// not the solver's table. Tolerance 1e-9 of the largest imposed displacement (round-off of a
// solve with condition number ~1e4, far below the pivoting tolerance's effect).
TEST(ContactWarmStart, EveryStepSatisfiesTheContactConditions) {
  const Plate& p = TopPlate();
  ContactSolver s(p.c, {.max_contacts = 160, .push_only = true});
  int checked = 0;
  for (int step = 0; step < 400; step += 1) {
    const std::vector<ContactInput> in = Patches(p, step);
    ASSERT_EQ(s.Solve(in), StepStatus::kOk);
    if (in.empty()) continue;
    std::vector<std::int32_t> nodes;
    double d_scale = 0.0;
    for (const auto& c : in) {
      nodes.push_back(c.node);
      d_scale = std::max(d_scale, c.u_m.norm());
    }
    std::vector<Eigen::Vector3d> u(in.size());
    ASSERT_EQ(s.Displacements(nodes, u), 0);
    for (std::size_t i = 0; i < in.size(); ++i) {
      const double gap = (u[i] - in[i].u_m).dot(in[i].n_out);  // > 0: surface above the tip
      const double fn = s.forces_N()[i].dot(in[i].n_out);        // < 0: pushes
      EXPECT_LT((s.forces_N()[i] - fn * in[i].n_out).norm(), 1e-12) << "frictionless";
      if (s.states()[i] == ContactState::kActive) {
        EXPECT_NEAR(gap, 0.0, 1e-9 * d_scale) << "step " << step;
        EXPECT_LE(fn, 0.0) << "step " << step;
      } else {
        ASSERT_EQ(s.states()[i], ContactState::kReleased);
        EXPECT_EQ(fn, 0.0);
        EXPECT_LE(gap, 1e-9 * d_scale) << "step " << step;
      }
      ++checked;
    }
  }
  EXPECT_GT(checked, 5000);
}

// With friction patches the solver keeps the factor of its last held set between steps and
// resumes the next factor after the rows of the nodes that stayed (ResumeFactorSpd; the rows
// are ordered for it). That must not change the answer: the same five patches, held in 3-D with
// a stick that strokes each fingertip's way (some patches stick, some slip, rims are released),
// against a new solver per step, which factors every held set whole in node order. Tolerance
// 1e-9 of the largest force (another row order: round-off only).
TEST(ContactWarmStart, FrictionPatchesWithAKeptFactorMatchAFreshSolvePerStep) {
  const Plate& p = TopPlate();
  const ContactSolverOptions opt{.max_contacts = 160, .push_only = true, .max_friction_patches = 5};
  ContactSolver kept(p.c, opt);
  std::vector<ContactInput> buf(64);
  int compared = 0, slipping = 0, sticking = 0;
  for (int step = 0; step < 300; ++step) {
    std::vector<ContactInput> in;
    std::vector<FrictionPatch> patches;
    const double t = 1e-3 * step;
    for (int f = 0; f < 5; ++f) {
      const double ang = (4.0 + f) * t + 1.2566 * f;
      const double rad = 0.008 + 0.003 * f;
      const Eigen::Vector3d c(0.03 + rad * std::cos(ang), 0.03 + rad * std::sin(ang), 0.02);
      const double depth = 0.00085 + 0.00115 * std::sin(20.0 * t + f);
      const PatchResult r = p.finder->Sphere(c, Eigen::Vector3d::UnitZ(), kR, depth, ContactMode::kNormalOnly, buf);
      if (r.count == 0) continue;
      const auto patch = static_cast<std::int32_t>(patches.size());
      for (std::int32_t k = 0; k < r.count; ++k) {
        ContactInput q = buf[static_cast<std::size_t>(k)];
        q.patch = patch;
        in.push_back(q);
      }
      // The stick grows along the stroke (0.1-0.6 mm: some patches stick, some slip).
      const Eigen::Vector3d along(-std::sin(ang), std::cos(ang), 0.0);
      const double stick = 1e-4 * (1.0 + f) * (1.0 + std::sin(7.0 * t + f));
      patches.push_back({Eigen::Vector3d::UnitZ(), stick * along, 0.8, 0.6, step % 3 == f % 3, 2e-5 * along});
    }
    ContactSolver fresh(p.c, opt);
    const StepStatus sk = kept.Solve(in, patches);
    const StepStatus sf = fresh.Solve(in, patches);
    ASSERT_EQ(sk, sf) << "step " << step;
    if (in.empty()) continue;
    ASSERT_EQ(sk, StepStatus::kOk) << "step " << step;
    ++compared;
    const double scale = std::max(MaxForce(fresh), 1e-12);
    for (std::size_t i = 0; i < in.size(); ++i) {
      ASSERT_LE((kept.forces_N()[i] - fresh.forces_N()[i]).norm(), 1e-9 * scale) << "step " << step << " contact " << i;
    }
    for (std::size_t a = 0; a < patches.size(); ++a) {
      ASSERT_EQ(kept.patch_states()[a].slipping, fresh.patch_states()[a].slipping) << "step " << step << " patch " << a;
      (fresh.patch_states()[a].slipping ? slipping : sticking) += 1;
    }
  }
  EXPECT_GT(compared, 250);
  EXPECT_GT(slipping, 50);  // both regimes were exercised
  EXPECT_GT(sticking, 50);
}

}  // namespace
}  // namespace handshare::fem
