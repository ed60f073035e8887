// The real-time contact solvers against the direct sparse solve (the exact static FEM answer),
// the paper's form against the symmetric form, and the edge cases: merged and rejected
// contacts, frictionless and push-only contact, regularization, near-incompressible material,
// sliver elements, and a million random steps.

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <random>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/elementary_displacement.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/surface_field.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

constexpr Material kMat{1e4, 0.3};

struct Model {
  test::Block block;
  std::shared_ptr<const Compliance> c64, c32;
};

Model MakeModel(const test::Block& b, const Material& m) {
  Model model{b, nullptr, nullptr};
  model.c64 = std::make_shared<Compliance>(Compliance::Precompute(b.mesh, m, b.fixed, {}));
  ComplianceOptions o;
  o.precision = Precision::kFloat32;
  model.c32 = std::make_shared<Compliance>(Compliance::Precompute(b.mesh, m, b.fixed, o));
  return model;
}

const Model& BoxModel() {
  static const Model m = MakeModel(test::MakeFixedBottomBox({0.04, 0.04, 0.02}, {8, 8, 4}), kMat);
  return m;
}

struct Errors {
  double force = 0.0, displacement = 0.0;
};

// Compares the compliance solver (forces and every surface displacement) with the direct solve.
Errors CompareWithDirect(const Model& model, const Compliance& c, const std::vector<ContactInput>& contacts) {
  auto cp = std::shared_ptr<const Compliance>(&c, [](const Compliance*) {});
  ContactSolver solver(cp, {.max_contacts = 16});
  EXPECT_EQ(solver.Solve(contacts), StepStatus::kOk);
  const test::DirectContact d = test::SolveDirect(model.block.mesh, kMat, model.block.fixed, contacts);
  std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
  std::vector<Eigen::Vector3d> u(c.num_nodes()), u_ref;
  EXPECT_TRUE(solver.SurfaceDisplacements(u));
  for (std::int32_t v : c.nodes()) u_ref.push_back(d.solution.u_m[v]);
  return {test::RelError(f, d.forces_N), test::RelError(u, u_ref)};
}

// Float64 storage: the compliance form is the exact FEM solution (Schur complement identity),
// so only round-off separates it from the direct solve: ~1e-14 measured, bound 1e-9.
TEST(ContactSolver, Float64MatchesDirectSparseSolve) {
  const Model& m = BoxModel();
  std::mt19937 rng(1);
  double worst_f = 0.0, worst_u = 0.0;
  for (int trial = 0; trial < 12; ++trial) {
    const Errors e = CompareWithDirect(m, *m.c64, test::RandomContacts(*m.c64, 1 + trial % 8, rng));
    worst_f = std::max(worst_f, e.force);
    worst_u = std::max(worst_u, e.displacement);
  }
  RecordProperty("worst_force_rel_error", test::Sci(worst_f));
  EXPECT_LT(worst_f, 1e-9);
  EXPECT_LT(worst_u, 1e-9);
}

// Float32 storage: entries rounded to 24 bits (6e-8 relative); C_cc has a condition number of a
// few here, so forces carry ~1e-7 error; bound 1e-5.
TEST(ContactSolver, Float32MatchesDirectSparseSolve) {
  const Model& m = BoxModel();
  std::mt19937 rng(2);
  for (int trial = 0; trial < 8; ++trial) {
    const Errors e = CompareWithDirect(m, *m.c32, test::RandomContacts(*m.c32, 1 + trial % 6, rng));
    EXPECT_LT(e.force, 1e-5);
    EXPECT_LT(e.displacement, 1e-5);
  }
}

TEST(ElementaryDisplacement, PaperFormAgreesWithSymmetricForm) {
  const Model& m = BoxModel();
  auto T = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*m.c64, Precision::kFloat64));
  // T^d_kk = I by construction (eq. 6 with n = k).
  EXPECT_LT((T->Td(4, 4) - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  ElementaryDisplacementSolver paper(T, 10);
  ContactSolver sym(m.c64, {.max_contacts = 10});
  std::mt19937 rng(3);
  for (int trial = 0; trial < 10; ++trial) {
    const auto contacts = test::RandomContacts(*m.c64, 1 + trial % 5, rng);
    ASSERT_EQ(paper.Solve(contacts), StepStatus::kOk);
    ASSERT_EQ(sym.Solve(contacts), StepStatus::kOk);
    std::vector<Eigen::Vector3d> fp(paper.forces_N().begin(), paper.forces_N().end());
    std::vector<Eigen::Vector3d> fs(sym.forces_N().begin(), sym.forces_N().end());
    EXPECT_LT(test::RelError(fp, fs), 1e-10);
    std::vector<Eigen::Vector3d> up(m.c64->num_nodes()), us(m.c64->num_nodes());
    ASSERT_TRUE(paper.SurfaceDisplacements(up));
    ASSERT_TRUE(sym.SurfaceDisplacements(us));
    EXPECT_LT(test::RelError(up, us), 1e-10);
    // The touched nodes sit exactly at d* (Cotin's correction).
    for (const auto& c : contacts) {
      EXPECT_LT((up[m.c64->SlotOf(c.node)] - c.u_m).norm(), 1e-10 * c.u_m.norm());
    }
  }
  // Float32 tensors: same numbers to float precision.
  auto T32 = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*m.c64, Precision::kFloat32));
  ElementaryDisplacementSolver paper32(T32, 10);
  const auto contacts = test::RandomContacts(*m.c64, 5, rng);
  ASSERT_EQ(paper32.Solve(contacts), StepStatus::kOk);
  ASSERT_EQ(sym.Solve(contacts), StepStatus::kOk);
  std::vector<Eigen::Vector3d> fp(paper32.forces_N().begin(), paper32.forces_N().end());
  std::vector<Eigen::Vector3d> fs(sym.forces_N().begin(), sym.forces_N().end());
  EXPECT_LT(test::RelError(fp, fs), 1e-5);
}

// Why the correction matters: plain superposition u_n = sum_k T^d_nk d*_k of the elementary
// solutions does not hold the touched nodes at d* when they interact (FEM-NOTES: 27-150% off).
TEST(ElementaryDisplacement, PlainSuperpositionIsWrongForCloseContacts) {
  const Model& m = BoxModel();
  auto T = std::make_shared<ElementaryDisplacementTensors>(
      ElementaryDisplacementTensors::FromCompliance(*m.c64, Precision::kFloat64));
  // Three neighbouring top nodes pushed down together.
  const auto top = NodesOnPlane(m.block.mesh, 2, 0.02);
  std::vector<std::int32_t> nodes = {top[40], top[41], top[49]};
  double worst = 0.0;
  for (std::int32_t a : nodes) {
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (std::int32_t k : nodes) u += T->Td(m.c64->SlotOf(a), m.c64->SlotOf(k)) * Eigen::Vector3d(0, 0, -1e-3);
    worst = std::max(worst, (u - Eigen::Vector3d(0, 0, -1e-3)).norm() / 1e-3);
  }
  EXPECT_GT(worst, 0.2);
}

TEST(ContactSolver, SameNodeTwiceIsMerged) {
  const Model& m = BoxModel();
  ContactSolver solver(m.c64, {.max_contacts = 8});
  const std::int32_t a = m.c64->nodes()[30], b = m.c64->nodes()[90];
  std::vector<ContactInput> twice = {{a, {0, 0, -1e-3}}, {b, {1e-4, 0, 0}}, {a, {0, 0, -3e-3}}};
  ASSERT_EQ(solver.Solve(twice), StepStatus::kOk);
  EXPECT_EQ(solver.num_unique(), 2);
  const Eigen::Vector3d fa1 = solver.forces_N()[0], fa2 = solver.forces_N()[2], fb = solver.forces_N()[1];
  std::vector<ContactInput> once = {{a, {0, 0, -2e-3}}, {b, {1e-4, 0, 0}}};
  ASSERT_EQ(solver.Solve(once), StepStatus::kOk);
  EXPECT_LT((fa1 + fa2 - solver.forces_N()[0]).norm(), 1e-12 * solver.forces_N()[0].norm());
  EXPECT_LT((fa1 - fa2).norm(), 1e-15);
  EXPECT_LT((fb - solver.forces_N()[1]).norm(), 1e-12 * fb.norm());
}

TEST(ContactSolver, FixedUnknownAndInvalidContactsAreRejectedNotThrown) {
  const Model& m = BoxModel();
  ContactSolver solver(m.c64, {.max_contacts = 4});
  const std::int32_t a = m.c64->nodes()[30];
  const std::int32_t fixed = m.block.fixed[3];
  const std::int32_t interior = 9 * 9 * 2 + 9 * 4 + 4;  // node (4, 4, 2): inside the box
  ASSERT_EQ(m.c64->SlotOf(interior), -1);
  std::vector<ContactInput> in = {{fixed, {0, 0, -1e-3}}, {a, {0, 0, -1e-3}}, {interior, {0, 0, -1e-3}},
                                  {-5, {0, 0, 0}}};
  EXPECT_EQ(solver.Solve(in), StepStatus::kSomeRejected);
  EXPECT_EQ(solver.states()[0], ContactState::kRejectedFixed);
  EXPECT_EQ(solver.states()[1], ContactState::kActive);
  EXPECT_EQ(solver.states()[2], ContactState::kRejectedUnknownNode);
  EXPECT_EQ(solver.states()[3], ContactState::kRejectedUnknownNode);
  EXPECT_EQ(solver.forces_N()[0].norm(), 0.0);
  const Eigen::Vector3d fa = solver.forces_N()[1];
  ASSERT_EQ(solver.Solve(std::vector<ContactInput>{{a, {0, 0, -1e-3}}}), StepStatus::kOk);
  EXPECT_LT((fa - solver.forces_N()[0]).norm(), 1e-14 * fa.norm());
  // NaN: nothing is rendered.
  in[1].u_m.x() = std::nan("");
  EXPECT_EQ(solver.Solve(in), StepStatus::kInvalidInput);
  EXPECT_EQ(solver.states()[1], ContactState::kRejectedInvalid);
  for (const auto& f : solver.forces_N()) EXPECT_EQ(f.norm(), 0.0);
  // A frictionless contact needs its normal.
  EXPECT_EQ(solver.Solve(std::vector<ContactInput>{{a, {0, 0, -1e-3}, Eigen::Vector3d::Zero(), ContactMode::kNormalOnly}}),
            StepStatus::kInvalidInput);
  // More inputs than max_contacts: the first ones are used.
  std::vector<ContactInput> many(6, ContactInput{a, {0, 0, -1e-3}});
  EXPECT_EQ(solver.Solve(many), StepStatus::kSomeRejected);
  EXPECT_EQ(solver.forces_N().size(), 4u);
  // Displacements: fixed nodes 0, unknown nodes NaN.
  std::vector<Eigen::Vector3d> u(3);
  EXPECT_EQ(solver.Displacements(std::vector<std::int32_t>{fixed, interior, a}, u), 1);
  EXPECT_EQ(u[0].norm(), 0.0);
  EXPECT_TRUE(std::isnan(u[1].x()));
  EXPECT_LT((u[2] - Eigen::Vector3d(0, 0, -1e-3)).norm(), 1e-12);
}

// Frictionless contacts impose n . u only. Consistency check against the exact solve: holding
// the contact nodes at the displacement the frictionless solve produced must need exactly the
// frictionless forces, which must be purely normal.
TEST(ContactSolver, FrictionlessContactIsConsistentWithTheDirectSolve) {
  const Model& m = BoxModel();
  ContactSolver solver(m.c64, {.max_contacts = 8});
  const auto top = NodesOnPlane(m.block.mesh, 2, 0.02);
  std::vector<ContactInput> in;
  for (int k : {30, 31, 40, 50}) {
    in.push_back({top[k], {0, 0, -1e-3 - 1e-4 * k}, Eigen::Vector3d::UnitZ(), ContactMode::kNormalOnly});
  }
  ASSERT_EQ(solver.Solve(in), StepStatus::kOk);
  std::vector<Eigen::Vector3d> u(in.size());
  std::vector<std::int32_t> nodes;
  for (const auto& c : in) nodes.push_back(c.node);
  ASSERT_EQ(solver.Displacements(nodes, u), 0);
  std::vector<ContactInput> held = in;
  for (std::size_t i = 0; i < in.size(); ++i) {
    EXPECT_NEAR(u[i].z(), in[i].u_m.z(), 1e-12);                 // normal component imposed
    EXPECT_LT(solver.forces_N()[i].head<2>().norm(), 1e-12);      // no tangential force
    held[i].u_m = u[i];
    held[i].mode = ContactMode::kFull3d;
  }
  const test::DirectContact d = test::SolveDirect(m.block.mesh, kMat, m.block.fixed, held);
  std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
  EXPECT_LT(test::RelError(f, d.forces_N), 1e-9);
}

// Push-only frictionless contact is a linear complementarity problem with a symmetric positive
// definite matrix, so it has exactly one solution: find it by enumerating all 2^m active sets
// with the plain solver and compare.
TEST(ContactSolver, PushOnlyMatchesBruteForceEnumeration) {
  const Model& m = BoxModel();
  const auto top = NodesOnPlane(m.block.mesh, 2, 0.02);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> depth(-1e-3, 2e-3);  // negative: the tip lifts off
  ContactSolver push(m.c64, {.max_contacts = 10, .push_only = true});
  ContactSolver plain(m.c64, {.max_contacts = 10});
  int released_total = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const int count = 3 + trial % 6;  // up to 8 contacts: 256 sets
    std::vector<ContactInput> in;
    std::uniform_int_distribution<int> pick(0, static_cast<int>(top.size()) - 1);
    while (static_cast<int>(in.size()) < count) {
      const std::int32_t v = top[pick(rng)];
      bool dup = false;
      for (const auto& c : in) dup = dup || c.node == v;
      if (dup) continue;
      in.push_back({v, {0, 0, -depth(rng)}, Eigen::Vector3d::UnitZ(), ContactMode::kNormalOnly});
    }
    ASSERT_NE(push.Solve(in), StepStatus::kNotConverged);
    int found = 0;
    for (int mask = 0; mask < (1 << count); ++mask) {
      std::vector<ContactInput> sub;
      for (int i = 0; i < count; ++i)
        if (mask & (1 << i)) sub.push_back(in[i]);
      ASSERT_EQ(plain.Solve(sub), StepStatus::kOk);
      std::vector<Eigen::Vector3d> u(in.size());
      std::vector<std::int32_t> nodes;
      for (const auto& c : in) nodes.push_back(c.node);
      plain.Displacements(nodes, u);
      bool ok = true;
      int k = 0;
      for (int i = 0; i < count; ++i) {
        if (mask & (1 << i)) {
          ok = ok && plain.forces_N()[k++].z() <= 1e-12;  // pushes (force into the object)
        } else {
          ok = ok && u[i].z() <= in[i].u_m.z() + 1e-12;   // surface stays below the tip
        }
      }
      if (!ok) continue;
      ++found;
      k = 0;
      for (int i = 0; i < count; ++i) {
        const Eigen::Vector3d want = (mask & (1 << i)) ? plain.forces_N()[k++] : Eigen::Vector3d::Zero();
        EXPECT_LT((push.forces_N()[i] - want).norm(), 1e-9 * (1.0 + want.norm()));
        EXPECT_EQ(push.states()[i], (mask & (1 << i)) ? ContactState::kActive : ContactState::kReleased);
        released_total += (mask & (1 << i)) ? 0 : 1;
      }
    }
    EXPECT_EQ(found, 1) << "trial " << trial;
  }
  EXPECT_GT(released_total, 5);  // the cases exercised releasing
}

// Push-only with sticking (full 3-D) contacts and random sideways drags: a sticking contact that
// would pull slips (friction needs pressure), then releases. After convergence: sticking and
// slipping contacts push, slipping ones carry no tangential force and sit at their imposed
// depth, and no released node is pushed into the tip.
TEST(ContactSolver, PushOnlySticking) {
  const Model& m = BoxModel();
  const auto top = NodesOnPlane(m.block.mesh, 2, 0.02);
  ContactSolver push(m.c64, {.max_contacts = 15, .push_only = true});
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> d(-1e-3, 1e-3);
  std::uniform_int_distribution<int> pick(0, static_cast<int>(top.size()) - 1);
  int counts[3] = {0, 0, 0};
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<ContactInput> in;
    for (int i = 0; i < 15; ++i) in.push_back({top[pick(rng)], {d(rng) * 0.3, d(rng) * 0.3, d(rng)}, Eigen::Vector3d::UnitZ()});
    ASSERT_EQ(push.Solve(in), StepStatus::kOk) << trial;
    std::vector<Eigen::Vector3d> u(in.size());
    std::vector<std::int32_t> nodes;
    for (const auto& c : in) nodes.push_back(c.node);
    push.Displacements(nodes, u);
    const double f_tol = 1e-9;  // N; forces here are ~0.1 N
    for (std::size_t i = 0; i < in.size(); ++i) {
      const ContactState st = push.states()[i];
      const Eigen::Vector3d& f = push.forces_N()[i];
      if (st == ContactState::kActive) {
        ++counts[0];
        EXPECT_LE(f.z(), f_tol);
      } else if (st == ContactState::kSlipping) {
        ++counts[1];
        EXPECT_LE(f.z(), f_tol);
        EXPECT_LE(f.head<2>().norm(), f_tol);
      } else {
        ASSERT_EQ(st, ContactState::kReleased);
        ++counts[2];
        EXPECT_EQ(f.norm(), 0.0);
      }
    }
    // Merged inputs share one node: check the per-node displacement conditions on distinct ones.
    for (std::size_t i = 0; i < in.size(); ++i) {
      bool first = true;
      for (std::size_t k = 0; k < i; ++k) first = first && in[k].node != in[i].node;
      if (!first) continue;
      double dz = 0.0;
      int mult = 0;
      for (const auto& c : in) {
        if (c.node == in[i].node) {
          dz += c.u_m.z();
          ++mult;
        }
      }
      dz /= mult;
      if (push.states()[i] == ContactState::kReleased) {
        EXPECT_LE(u[i].z() - dz, 1e-12);
      }
      if (push.states()[i] == ContactState::kSlipping) {
        EXPECT_NEAR(u[i].z(), dz, 1e-12);
      }
    }
  }
  // The random drags exercised all three outcomes.
  EXPECT_GT(counts[0], 0);
  EXPECT_GT(counts[1], 0);
  EXPECT_GT(counts[2], 0);
}

// Adjacent touched nodes with different displacements are well posed but stiff (large opposing
// forces); regularization (C_cc + eps I) f = d* and the virtual coupling (C_cc + I/k_c) f = d*
// bound them, converge to the exact answer as eps -> 0, and the coupling identity holds:
// node displacement + f / k_c = d*.
TEST(ContactSolver, AdjacentContactsRegularizationAndCoupling) {
  const Model& m = BoxModel();
  const auto top = NodesOnPlane(m.block.mesh, 2, 0.02);
  std::vector<ContactInput> in = {{top[40], {0, 0, -1e-3}}, {top[41], {0, 0, 1e-3}}, {top[49], {5e-4, 0, -1e-3}}};
  ContactSolver exact(m.c64, {.max_contacts = 3});
  ASSERT_EQ(exact.Solve(in), StepStatus::kOk);
  std::vector<Eigen::Vector3d> f0(exact.forces_N().begin(), exact.forces_N().end());
  for (const auto& f : f0) EXPECT_TRUE(f.allFinite());
  const double c_scale = m.c64->Block(m.c64->SlotOf(top[40]), m.c64->SlotOf(top[40])).norm();
  double prev = 1e300;
  for (double rel : {1.0, 1e-1, 1e-2, 1e-3, 1e-4}) {
    ContactSolver reg(m.c64, {.max_contacts = 3, .regularization_m_per_N = rel * c_scale});
    ASSERT_EQ(reg.Solve(in), StepStatus::kOk);
    std::vector<Eigen::Vector3d> f(reg.forces_N().begin(), reg.forces_N().end());
    const double err = test::RelError(f, f0);
    EXPECT_LT(err, prev);  // monotone convergence to the exact forces
    prev = err;
    // The regularized system is a softer spring in series: it never needs more energy.
    double e_reg = 0, e_exact = 0;
    for (std::size_t i = 0; i < in.size(); ++i) {
      e_reg += f[i].dot(in[i].u_m);
      e_exact += f0[i].dot(in[i].u_m);
    }
    EXPECT_LE(e_reg, e_exact * (1 + 1e-12));
  }
  EXPECT_LT(prev, 1e-2);
  const double kc = 50.0;  // N/m
  ContactSolver coupled(m.c64, {.max_contacts = 3, .coupling_stiffness_N_per_m = kc});
  ASSERT_EQ(coupled.Solve(in), StepStatus::kOk);
  std::vector<Eigen::Vector3d> u(3);
  coupled.Displacements(std::vector<std::int32_t>{top[40], top[41], top[49]}, u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_LT((u[i] + coupled.forces_N()[i] / kc - in[i].u_m).norm(), 1e-12);
  }
}

// Near-incompressible material (nu = 0.499): K is ~1000x worse conditioned, the compliance form
// must still match the direct solve. Bound 1e-7 (measured ~1e-12).
TEST(ContactSolver, NearIncompressibleMatchesDirect) {
  const Material soft{1e4, 0.499};
  const test::Block b = test::MakeFixedBottomBox({0.02, 0.02, 0.01}, {5, 5, 3});
  auto c = std::make_shared<Compliance>(Compliance::Precompute(b.mesh, soft, b.fixed, {}));
  ContactSolver solver(c, {.max_contacts = 6});
  std::mt19937 rng(8);
  for (int trial = 0; trial < 5; ++trial) {
    const auto in = test::RandomContacts(*c, 2 + trial, rng);
    ASSERT_EQ(solver.Solve(in), StepStatus::kOk);
    const test::DirectContact d = test::SolveDirect(b.mesh, soft, b.fixed, in);
    std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
    EXPECT_LT(test::RelError(f, d.forces_N), 1e-7);
  }
}

// Slivers: a layer 1000x thinner than the others gives tetrahedra with aspect ratio ~1000.
// Valid (positive volume), badly conditioned; the solve must stay finite and exact. Bound 1e-7.
TEST(ContactSolver, SliverElementsMatchDirect) {
  const std::vector<double> xy = {0, 0.005, 0.01, 0.015, 0.02};
  const std::vector<double> z = {0, 0.005, 0.005 + 5e-6, 0.01};
  test::Block b{MakeGridMesh(xy, xy, z), {}};
  b.fixed = NodesOnPlane(b.mesh, 2, 0.0);
  double min_vol = 1e300;
  for (const auto& t : b.mesh.tets()) {
    const auto& p = b.mesh.positions_m();
    min_vol = std::min(min_vol, SignedVolume(p[t[0]], p[t[1]], p[t[2]], p[t[3]]));
  }
  EXPECT_LT(min_vol, 1e-3 * 0.005 * 0.005 * 0.005 / 6);  // the slivers are there
  auto c = std::make_shared<Compliance>(Compliance::Precompute(b.mesh, kMat, b.fixed, {}));
  ContactSolver solver(c, {.max_contacts = 6});
  std::mt19937 rng(9);
  for (int trial = 0; trial < 5; ++trial) {
    const auto in = test::RandomContacts(*c, 1 + trial, rng);
    ASSERT_EQ(solver.Solve(in), StepStatus::kOk);
    const test::DirectContact d = test::SolveDirect(b.mesh, kMat, b.fixed, in);
    std::vector<Eigen::Vector3d> f(solver.forces_N().begin(), solver.forces_N().end());
    EXPECT_LT(test::RelError(f, d.forces_N), 1e-7);
  }
}

// A million random steps (random nodes, repeats, fixed nodes, 1-5 contacts, all modes): never a
// NaN or Inf, and forces bounded. Bound: f = S d* with S = C_cc^-1 the Schur complement of K_ff,
// whose eigenvalues never exceed K_ff's, so ||f|| <= lambda_max(K) ||d*||; lambda_max is bounded
// by the largest absolute row sum of K (Gershgorin). float32 storage perturbs C by ~1e-7: 1% slack.
TEST(ContactSolver, MillionRandomStepsStayFiniteAndBounded) {
  const Model& m = BoxModel();
  const double lambda_bound = test::StiffnessEigenBound(m.block.mesh, kMat);

  ContactSolver sticking(m.c32, {.max_contacts = 5});
  ContactSolver pushing(m.c32, {.max_contacts = 5, .regularization_m_per_N = 1e-6, .push_only = true});
  std::mt19937 rng(10);
  std::uniform_int_distribution<int> count(1, 5);
  std::uniform_int_distribution<std::int32_t> node(0, m.block.mesh.num_nodes() - 1);
  std::uniform_real_distribution<double> u(-2e-3, 2e-3);
  std::vector<ContactInput> in(5);
  long bad = 0, not_ok = 0;
  double worst_ratio = 0.0;
  constexpr int kSteps = 1000000;
  for (int step = 0; step < kSteps; ++step) {
    const int mcount = count(rng);
    double d_norm2 = 0.0;
    for (int i = 0; i < mcount; ++i) {
      in[i].node = (i > 0 && step % 7 == 0) ? in[0].node : node(rng);  // repeats
      in[i].u_m = {u(rng), u(rng), u(rng)};
      in[i].n_out = Eigen::Vector3d::UnitZ();
      in[i].mode = (step & 1) ? ContactMode::kNormalOnly : ContactMode::kFull3d;
      d_norm2 += in[i].u_m.squaredNorm();
    }
    ContactSolver& s = (step % 3 == 0) ? pushing : sticking;
    const StepStatus st = s.Solve(std::span(in.data(), static_cast<std::size_t>(mcount)));
    if (st != StepStatus::kOk && st != StepStatus::kSomeRejected) ++not_ok;
    double f_norm2 = 0.0;
    for (const auto& f : s.forces_N()) {
      if (!f.allFinite()) ++bad;
      f_norm2 += f.squaredNorm();
    }
    if (d_norm2 > 0) worst_ratio = std::max(worst_ratio, std::sqrt(f_norm2 / d_norm2));
  }
  RecordProperty("worst_force_per_displacement_N_per_m", test::Sci(worst_ratio));
  EXPECT_EQ(bad, 0);
  EXPECT_EQ(not_ok, 0);
  EXPECT_LT(worst_ratio, lambda_bound);
  EXPECT_GT(worst_ratio, 0.0);
}

// The AVX-512 kernel (float32 storage, when the CPU has it) and the portable one compute the same
// field; more loads than one SIMD chunk (32), and an invalid slot that must be skipped. Bound
// 1e-6: the SIMD kernel accumulates in float (relative 6e-8 per operation over ~100 terms).
TEST(SurfaceField, SimdAndPortableKernelsAgree) {
  const Model& m = BoxModel();
  SurfaceField simd(m.c32, true), portable(m.c32, false), f64(m.c64, true);
  EXPECT_EQ(simd.uses_simd(), CpuHasAvx512());
  EXPECT_FALSE(portable.uses_simd());
  EXPECT_FALSE(f64.uses_simd());
  std::mt19937 rng(11);
  std::uniform_int_distribution<std::int32_t> slot(0, m.c32->num_nodes() - 1);
  std::uniform_real_distribution<double> f(-1.0, 1.0);
  std::vector<NodeLoad> loads;
  for (int i = 0; i < 40; ++i) loads.push_back({slot(rng), {f(rng), f(rng), f(rng)}});
  loads.push_back({m.c32->num_nodes() + 5, {1, 1, 1}});
  loads.push_back({0, {0.5, 0, 0}});
  loads.push_back({m.c32->num_nodes() - 1, {0, 0, 0.5}});
  std::vector<Eigen::Vector3d> a(m.c32->num_nodes()), b(m.c32->num_nodes()), c(m.c32->num_nodes());
  ASSERT_TRUE(simd.Evaluate(loads, a));
  ASSERT_TRUE(portable.Evaluate(loads, b));
  ASSERT_TRUE(f64.Evaluate(loads, c));
  EXPECT_LT(test::RelError(a, b), 1e-6);
  EXPECT_LT(test::RelError(b, c), 1e-6);
  std::vector<Eigen::Vector3d> wrong(3);
  EXPECT_FALSE(simd.Evaluate(loads, wrong));
  // The solver's loads() reproduce its own surface field through a separate SurfaceField.
  ContactSolver solver(m.c32, {.max_contacts = 8});
  ASSERT_EQ(solver.Solve(test::RandomContacts(*m.c32, 6, rng)), StepStatus::kOk);
  ASSERT_EQ(solver.loads().size(), 6u);
  ASSERT_TRUE(solver.SurfaceDisplacements(a));
  ASSERT_TRUE(portable.Evaluate(solver.loads(), b));
  EXPECT_LT(test::RelError(a, b), 1e-6);
}

TEST(ContactSolver, OptionsAreValidated) {
  const Model& m = BoxModel();
  EXPECT_THROW(ContactSolver(nullptr, {}), InputError);
  EXPECT_THROW(ContactSolver(m.c64, {.max_contacts = 0}), InputError);
  EXPECT_THROW(ContactSolver(m.c64, {.regularization_m_per_N = -1.0}), InputError);
  EXPECT_THROW(ContactSolver(m.c64, {.coupling_stiffness_N_per_m = std::nan("")}), InputError);
}

}  // namespace
}  // namespace handshare::fem
