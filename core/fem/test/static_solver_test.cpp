// Element stiffness, assembly and the direct static solve against analytic solutions:
// the uniaxial bar (exact for linear tetrahedra) and the Timoshenko cantilever (approximate:
// linear tetrahedra are too stiff in bending).

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/error.hpp"
#include "handshare/fem/static_solver.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

// 6 rigid-body modes of the given nodes (3 translations, 3 small rotations), 3n x 6.
Eigen::MatrixXd RigidModes(const std::vector<Eigen::Vector3d>& p) {
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(3 * static_cast<Eigen::Index>(p.size()), 6);
  for (std::size_t i = 0; i < p.size(); ++i) {
    R.block<3, 3>(3 * i, 0).setIdentity();
    for (int a = 0; a < 3; ++a) {
      R.block<3, 1>(3 * i, 3 + a) = Eigen::Vector3d::Unit(a).cross(p[i]);
    }
  }
  return R;
}

TEST(Element, StiffnessIsSymmetricWithSixRigidModes) {
  const std::vector<Eigen::Vector3d> p = {{0.1, 0, 0}, {1.2, 0.1, 0}, {0.2, 0.9, 0.1}, {0.3, 0.2, 1.1}};
  const Material m{2e5, 0.35};
  const auto K = TetStiffness(p[0], p[1], p[2], p[3], m);
  EXPECT_LT((K - K.transpose()).norm(), 1e-12 * K.norm());
  EXPECT_LT((K * RigidModes(p)).norm(), 1e-12 * K.norm());
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 12, 12>> es(K);
  // Eigenvalues ascending: 6 (numerically) zero, 6 positive.
  EXPECT_LT(std::abs(es.eigenvalues()[5]), 1e-10 * es.eigenvalues()[11]);
  EXPECT_GT(es.eigenvalues()[6], 1e-6 * es.eigenvalues()[11]);
}

TEST(Element, UniformStrainEnergyMatchesContinuum) {
  // For u = eps x e_x (all other components 0): energy density 1/2 (lambda + 2 mu) eps^2.
  const std::vector<Eigen::Vector3d> p = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const Material m{1e4, 0.3};
  const auto K = TetStiffness(p[0], p[1], p[2], p[3], m);
  const double eps = 1e-3;
  Eigen::Matrix<double, 12, 1> u = Eigen::Matrix<double, 12, 1>::Zero();
  for (int i = 0; i < 4; ++i) u[3 * i] = eps * p[i].x();
  const double energy = 0.5 * u.dot(K * u);
  const double expected = 0.5 * (m.lambda_Pa() + 2 * m.G_Pa()) * eps * eps * (1.0 / 6.0);
  EXPECT_NEAR(energy, expected, 1e-12 * expected);
}

TEST(Assembly, GlobalStiffnessHasRigidModesAndIsSymmetric) {
  const TetMesh mesh = MakeBoxMesh({0.02, 0.03, 0.04}, {2, 3, 4});
  const auto K = AssembleStiffness(mesh, {1e4, 0.3});
  const Eigen::MatrixXd Kd = Eigen::MatrixXd(K);
  EXPECT_LT((Kd - Kd.transpose()).norm(), 1e-13 * Kd.norm());
  EXPECT_LT((Kd * RigidModes(mesh.positions_m())).norm(), 1e-12 * Kd.norm());
}

TEST(Assembly, MaterialValidation) {
  EXPECT_THROW((Material{-1.0, 0.3}.Validate()), InputError);
  EXPECT_THROW((Material{1e4, 0.5}.Validate()), InputError);
  EXPECT_THROW((Material{1e4, std::nan("")}.Validate()), InputError);
  EXPECT_NO_THROW((Material{1e4, 0.499}.Validate()));
}

// A bar 0.1 x 0.02 x 0.02 m with its interior nodes moved at random (the patch test on
// distorted elements): imposing the exact uniaxial field u = (eps x, -nu eps y, -nu eps z) on
// both end faces, linear tetrahedra must reproduce it everywhere (it is in their span), and the
// end reaction must be E A eps. Tolerance 1e-10 relative: round-off of a ~3000-DOF solve.
TEST(StaticSolve, UniaxialBarIsExact) {
  const double L = 0.1, b = 0.02, E = 1e4, nu = 0.3, eps = 1e-3;
  TetMesh grid = MakeBoxMesh({L, b, b}, {10, 3, 3});
  std::vector<Eigen::Vector3d> p = grid.positions_m();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.1, 0.1);
  const double h = b / 3;
  for (auto& x : p) {
    for (int a = 0; a < 3; ++a) {
      const double extent = a == 0 ? L : b;
      if (x[a] > 1e-12 && x[a] < extent - 1e-12) x[a] += jitter(rng) * h;
    }
  }
  const TetMesh mesh(p, grid.tets(), {}, "distorted bar");
  StaticProblem prob;
  auto exact = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3d(eps * x.x(), -nu * eps * x.y(), -nu * eps * x.z());
  };
  for (std::int32_t v : NodesOnPlane(mesh, 0, 0.0)) prob.imposed_u_m.push_back({v, exact(p[v])});
  const auto far_end = NodesOnPlane(mesh, 0, L);
  for (std::int32_t v : far_end) prob.imposed_u_m.push_back({v, exact(p[v])});
  const StaticSolution s = SolveStatic(mesh, {E, nu}, prob);
  double max_err = 0.0;
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    max_err = std::max(max_err, (s.u_m[v] - exact(p[v])).norm());
  }
  EXPECT_LT(max_err, 1e-10 * eps * L);
  Eigen::Vector3d reaction = Eigen::Vector3d::Zero();
  for (std::int32_t v : far_end) reaction += s.reaction_N[v];
  EXPECT_NEAR(reaction.x(), E * b * b * eps, 1e-9 * E * b * b * eps);
  EXPECT_NEAR(reaction.y(), 0.0, 1e-9 * E * b * b * eps);
  EXPECT_NEAR(reaction.z(), 0.0, 1e-9 * E * b * b * eps);
}

// Cantilever clamped at x = 0, end load P (downward, -z) spread over the end face by area.
struct CantileverResult {
  double fem_m;
  double timoshenko_m;
};

CantileverResult Cantilever(int nx, int nyz, double nu) {
  const double L = 0.2, h = 0.02, E = 1e4, P = 1e-2;
  const TetMesh mesh = MakeBoxMesh({L, h, h}, {nx, nyz, nyz});
  StaticProblem prob;
  prob.fixed_nodes = NodesOnPlane(mesh, 0, 0.0);
  // Consistent nodal loads of a uniform traction on the end face: area / 3 per triangle vertex.
  const Surface s = ExtractSurface(mesh);
  std::vector<double> share(mesh.num_nodes(), 0.0);
  const auto& p = mesh.positions_m();
  for (const auto& t : s.triangles) {
    if (std::abs(p[t[0]].x() - L) < 1e-12 && std::abs(p[t[1]].x() - L) < 1e-12 &&
        std::abs(p[t[2]].x() - L) < 1e-12) {
      const double area = 0.5 * (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]).norm();
      for (std::int32_t v : t) share[v] += area / 3.0;
    }
  }
  const auto end = NodesOnPlane(mesh, 0, L);
  for (std::int32_t v : end) prob.forces_N.push_back({v, {0, 0, -P * share[v] / (h * h)}});
  const StaticSolution sol = SolveStatic(mesh, {E, nu}, prob);
  double w = 0.0;  // mean deflection of the end face (a rigid-body-like average of the section)
  for (std::int32_t v : end) w += -sol.u_m[v].z() * share[v] / (h * h);
  const double I = h * h * h * h / 12.0, A = h * h, G = E / (2 * (1 + nu));
  const double kappa = 10 * (1 + nu) / (12 + 11 * nu);  // rectangular section (Cowper)
  return {w, P * L * L * L / (3 * E * I) + P * L / (kappa * G * A)};
}

// Linear tetrahedra are too stiff in bending (constant strain per element), so the FEM
// deflection converges to Timoshenko's from below. Measured here (L/h = 10, nu = 0.3): 50% at
// 20x2x2 cells, 79% at 40x4x4, 93% at 80x8x8 (the figure FEM-NOTES gives for an 80x8 C3D4 mesh),
// 96% at 120x12x12. The test asserts convergence from below and at least 90% on 80x8x8; the upper
// bound 1.02 allows for the clamped root and the end-load distribution, which Timoshenko's
// beam formula does not model (about 1%).
TEST(StaticSolve, CantileverApproachesTimoshenkoFromBelow) {
  const CantileverResult coarse = Cantilever(40, 4, 0.3);
  const CantileverResult fine = Cantilever(80, 8, 0.3);
  const double r_coarse = coarse.fem_m / coarse.timoshenko_m;
  const double r_fine = fine.fem_m / fine.timoshenko_m;
  RecordProperty("ratio_40x4x4", test::Sci(r_coarse));
  RecordProperty("ratio_80x8x8", test::Sci(r_fine));
  EXPECT_LT(r_coarse, r_fine);
  EXPECT_GT(r_fine, 0.90);
  EXPECT_LT(r_fine, 1.02);
}

// Volumetric locking: as nu -> 0.5 linear tetrahedra lock (FEM-NOTES: 16% of Timoshenko at
// nu = 0.499 on 80x8; measured here 15.6% on 80x8x8). The solve must stay finite and positive;
// the deflection ratio must drop
// well below the nu = 0.3 one. This documents a limitation; it is not a tolerance to relax.
TEST(StaticSolve, CantileverLocksNearIncompressible) {
  const CantileverResult r3 = Cantilever(80, 8, 0.3);
  const CantileverResult r499 = Cantilever(80, 8, 0.499);
  const double ratio3 = r3.fem_m / r3.timoshenko_m;
  const double ratio499 = r499.fem_m / r499.timoshenko_m;
  RecordProperty("ratio_nu0499", test::Sci(ratio499));
  EXPECT_TRUE(std::isfinite(ratio499));
  EXPECT_GT(ratio499, 0.0);
  EXPECT_LT(ratio499, 0.5 * ratio3);
}

TEST(StaticSolve, BadProblemsAreRejected) {
  const TetMesh mesh = MakeBoxMesh({1, 1, 1}, {1, 1, 1});
  const Material m{1e4, 0.3};
  // Nothing fixed: K is singular.
  try {
    SolveStatic(mesh, m, {});
    ADD_FAILURE() << "no exception";
  } catch (const FemError& e) {
    EXPECT_NE(std::string(e.what()).find("not positive definite"), std::string::npos) << e.what();
  }
  StaticProblem p;
  p.fixed_nodes = {0, 1, 2};
  p.imposed_u_m = {{2, {0, 0, 1e-3}}};
  EXPECT_THROW(SolveStatic(mesh, m, p), InputError);  // fixed and imposed
  p.imposed_u_m = {{7, {0, 0, 1e-3}}, {7, {0, 0, 1e-3}}};
  EXPECT_THROW(SolveStatic(mesh, m, p), InputError);  // imposed twice
  p.imposed_u_m = {{99, {0, 0, 1e-3}}};
  EXPECT_THROW(SolveStatic(mesh, m, p), InputError);  // out of range
  p.imposed_u_m = {{7, {0, std::nan(""), 1e-3}}};
  EXPECT_THROW(SolveStatic(mesh, m, p), InputError);  // NaN displacement
}

}  // namespace
}  // namespace handshare::fem
