// An independent oracle: CalculiX (ccx, C3D4 elements) on the same mesh and loads.
// The .inp is written with 12 significant digits (ccx cuts fields longer than 20 characters)
// and read back by our own reader, so both solvers see bit-identical geometry and material.
// ccx prints 7 significant digits to job.dat (relative rounding <= 5e-7 per entry); both are
// direct solves (round-off ~1e-12), so 1e-5 relative (norm over all nodes) is a safe bound that
// would still catch any modelling difference (element formulation, sign, units).

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <random>
#include <sstream>
#include <string>

#include "handshare/fem/calculix.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/mesh_io.hpp"
#include "handshare/fem/static_solver.hpp"
#include "test_util.hpp"

namespace handshare::fem {
namespace {

bool HaveCcx() { return std::system("command -v ccx > /dev/null 2>&1") == 0; }

std::string G12(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.12g", v);
  return b;
}

// Runs ccx on the case in a scratch folder (the deck writer and reader of calculix.hpp).
CcxTables RunCcx(const TetMesh& mesh, const CcxCase& c, const test::TempDir& dir) {
  const CcxResult r = RunCalculix(mesh, c, dir.path());
  EXPECT_TRUE(r.converged) << r.message;
  auto tables = ReadCalculixDat(dir.path() / "job.dat");
  EXPECT_EQ(tables.u_m.size(), static_cast<std::size_t>(mesh.num_nodes()));
  return tables;
}

double CompareToCcx(const TetMesh& mesh, const CcxCase& c, std::string* detail) {
  test::TempDir dir;
  auto tables = RunCcx(mesh, c, dir);
  // Our solver on the mesh as written (12 digits) and re-read.
  const TetMesh ours_mesh = ReadAbaqusInp(dir.path() / "job.inp");
  EXPECT_EQ(ours_mesh.num_nodes(), mesh.num_nodes());
  // The deck numbers nodes index + 1.
  auto remap = [&](std::int32_t v) { return *ours_mesh.IndexOfId(v + 1); };
  StaticProblem p;
  for (std::int32_t v : c.fixed) p.fixed_nodes.push_back(remap(v));
  for (const auto& iv : c.imposed) p.imposed_u_m.push_back({remap(iv.node), iv.value});
  for (const auto& f : c.forces) p.forces_N.push_back({remap(f.node), f.value});
  const Material m{std::stod(G12(c.material.E_Pa)), std::stod(G12(c.material.nu))};
  const StaticSolution s = SolveStatic(ours_mesh, m, p);

  std::vector<Eigen::Vector3d> a, b, ra, rb;
  for (std::int32_t v = 0; v < ours_mesh.num_nodes(); ++v) {
    a.push_back(s.u_m[v]);
    b.push_back(tables.u_m[ours_mesh.node_ids()[v]]);
  }
  for (const auto& iv : p.imposed_u_m) {
    ra.push_back(s.reaction_N[iv.node]);
    rb.push_back(tables.reaction_N[ours_mesh.node_ids()[iv.node]]);
  }
  const double eu = test::RelError(a, b);
  const double er = ra.empty() ? 0.0 : test::RelError(ra, rb);
  *detail = "displacement rel. error " + test::Sci(eu) + ", reaction rel. error " + test::Sci(er);
  return std::max(eu, er);
}

// A block on a distorted grid (non-uniform spacing, jittered interior nodes), bottom fixed.
TetMesh DistortedBlock() {
  std::vector<double> xs = {0, 0.003, 0.007, 0.01, 0.012, 0.016, 0.02};
  std::vector<double> ys = {0, 0.004, 0.006, 0.011, 0.015, 0.02};
  std::vector<double> zs = {0, 0.003, 0.0065, 0.01};
  const TetMesh grid = MakeGridMesh(xs, ys, zs);
  std::vector<Eigen::Vector3d> p = grid.positions_m();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> j(-3e-4, 3e-4);
  for (auto& x : p) {
    if (x.x() > 0 && x.x() < 0.02 && x.y() > 0 && x.y() < 0.02 && x.z() > 0 && x.z() < 0.01) {
      x += Eigen::Vector3d(j(rng), j(rng), j(rng));
    }
  }
  return TetMesh(p, grid.tets(), {}, "distorted block");
}

TEST(CalculiX, ImposedFingertipDisplacementsAgree) {
  if (!HaveCcx()) GTEST_SKIP() << "ccx not installed (Debian package calculix-ccx)";
  const TetMesh mesh = DistortedBlock();
  CcxCase c;
  c.material = {12345.6789, 0.3};
  c.fixed = NodesOnPlane(mesh, 2, 0.0);
  // Five top nodes pushed in and sideways, like five fingertips.
  const auto top = NodesOnPlane(mesh, 2, 0.01);
  for (int k = 0; k < 5; ++k) {
    const std::int32_t v = top[static_cast<std::size_t>(3 + 7 * k) % top.size()];
    c.imposed.push_back({v, {1e-4 * (k - 2), 5e-5 * k, -2e-4 - 1e-4 * k}});
  }
  std::string detail;
  EXPECT_LT(CompareToCcx(mesh, c, &detail), 1e-5) << detail;
  RecordProperty("detail", detail);
}

// A fingertip patch with friction, dragged sideways (the real-time compliance solver with its
// FrictionPatch, sticking, then slipping), against ccx with the displacements it held imposed:
// the patch's nodal forces and the surface field agree. Float64 compliance, so the bound is
// ccx's printed precision, as above.
TEST(CalculiX, FrictionPatchDraggedSidewaysAgrees) {
  if (!HaveCcx()) GTEST_SKIP() << "ccx not installed (Debian package calculix-ccx)";
  const TetMesh mesh = DistortedBlock();
  const Material mat{12345.6789, 0.3};  // 12 digits: what ccx reads
  const auto fixed = NodesOnPlane(mesh, 2, 0.0);
  auto C = std::make_shared<const Compliance>(Compliance::Precompute(mesh, mat, fixed, {}));
  // The top nodes within 5 mm of (10, 11) mm, pressed by a paraboloid (R = 20 mm, 0.4 mm deep).
  std::vector<ContactInput> in;
  for (std::int32_t v : NodesOnPlane(mesh, 2, 0.01)) {
    const Eigen::Vector3d& x = mesh.positions_m()[v];
    const double r = std::hypot(x.x() - 0.010, x.y() - 0.011), w = 4e-4 - r * r / 0.04;
    if (r < 0.005 && w > 0.0) in.push_back({v, {0, 0, -w}, Eigen::Vector3d::UnitZ(), ContactMode::kNormalOnly, 0});
  }
  ASSERT_GE(in.size(), 3u);
  ContactSolver solver(C, {.max_contacts = 32, .push_only = true});
  for (double mu : {5.0, 0.3}) {  // sticks, then slips
    const FrictionPatch patch{Eigen::Vector3d::UnitZ(), Eigen::Vector3d(3e-4, -1e-4, 0), mu, mu, false};
    ASSERT_EQ(solver.Solve(in, std::span(&patch, 1)), StepStatus::kOk);
    EXPECT_EQ(solver.patch_states()[0].slipping, mu < 1.0);
    CcxCase c;
    c.material = mat;
    c.fixed = fixed;
    std::vector<Eigen::Vector3d> ours_f;
    for (std::size_t i = 0; i < in.size(); ++i) {
      if (solver.states()[i] == ContactState::kReleased) continue;
      c.imposed.push_back({in[i].node, in[i].u_m + solver.patch_states()[0].slide_m});
      ours_f.push_back(solver.forces_N()[i]);
    }
    test::TempDir dir;
    auto tables = RunCcx(mesh, c, dir);
    std::vector<Eigen::Vector3d> ccx_f, ours_u, ccx_u;
    for (const auto& iv : c.imposed) ccx_f.push_back(tables.reaction_N[iv.node + 1]);
    std::vector<Eigen::Vector3d> field(static_cast<std::size_t>(C->num_nodes()));
    ASSERT_TRUE(solver.SurfaceDisplacements(field));
    for (std::int32_t k = 0; k < C->num_nodes(); ++k) {
      ours_u.push_back(field[static_cast<std::size_t>(k)]);
      ccx_u.push_back(tables.u_m[C->nodes()[k] + 1]);
    }
    const double ef = test::RelError(ours_f, ccx_f), eu = test::RelError(ours_u, ccx_u);
    RecordProperty(mu < 1.0 ? "slipping" : "sticking", "force rel. error " + test::Sci(ef) + ", field " + test::Sci(eu));
    EXPECT_LT(ef, 1e-5) << "mu " << mu;
    EXPECT_LT(eu, 1e-5) << "mu " << mu;
    // The drag is real: a tangential force of a good fraction of the normal one.
    const Eigen::Vector3d F = solver.patch_states()[0].force_N;
    EXPECT_GT(F.head<2>().norm(), 0.1 * -F.z()) << "mu " << mu;
  }
}

// The nonlinear decks (NLGEOM; neo-Hooke of the same small-strain moduli) against the linear
// one: the 3 x 3 top nodes within 4.5 mm of a point pressed straight down. At 10 nm (strain
// ~1e-6) all three must give the linear reaction to 1e-4 (measured 2e-6 and 7e-7): a
// neo-Hookean solid with wrong constants (C10 = G instead of G / 2) or any other modelling slip
// would be off by tens of percent, while the geometric terms are of the order of the strain. At
// 1 mm (a tenth of the block's height) both nonlinear models must differ from the linear one by
// more than 1 % (measured 20 % and 8 %): a deck that lost NLGEOM or the hyperelastic material
// would not.
TEST(CalculiX, NonlinearModelsMeetTheLinearOneAtSmallStrainAndLeaveItAtLarge) {
  if (!HaveCcx()) GTEST_SKIP() << "ccx not installed (Debian package calculix-ccx)";
  const TetMesh mesh = DistortedBlock();
  const auto fixed = NodesOnPlane(mesh, 2, 0.0);
  std::vector<std::int32_t> pressed;
  for (std::int32_t v : NodesOnPlane(mesh, 2, 0.01)) {
    const Eigen::Vector3d& x = mesh.positions_m()[static_cast<std::size_t>(v)];
    if (std::abs(x.x() - 0.01) < 0.0045 && std::abs(x.y() - 0.011) < 0.0045) pressed.push_back(v);
  }
  ASSERT_GE(pressed.size(), 4u);
  auto total_reaction = [&](CcxModel model, double depth_m) {
    CcxCase c;
    c.material = {30000.0, 0.45};
    c.model = model;
    c.fixed = fixed;
    for (std::int32_t v : pressed) c.imposed.push_back({v, {0.0, 0.0, -depth_m}});
    test::TempDir dir;
    const CcxResult r = RunCalculix(mesh, c, dir.path());
    EXPECT_TRUE(r.converged) << CcxModelName(model) << " at " << depth_m << " m: " << r.message;
    Eigen::Vector3d F = Eigen::Vector3d::Zero();
    for (const auto& f : r.reaction_N) F += f;
    return F;
  };
  for (double depth_m : {1e-8, 1e-3}) {
    const Eigen::Vector3d lin = total_reaction(CcxModel::kLinear, depth_m);
    ASSERT_GT(-lin.z(), 0.0);
    for (CcxModel model : {CcxModel::kNlgeom, CcxModel::kNeoHooke}) {
      const double err = (total_reaction(model, depth_m) - lin).norm() / lin.norm();
      RecordProperty(std::string(CcxModelName(model)) + "_at_" + G12(depth_m), test::Sci(err));
      if (depth_m < 1e-6) {
        EXPECT_LT(err, 1e-4) << CcxModelName(model);
      } else {
        EXPECT_GT(err, 0.01) << CcxModelName(model);
      }
    }
  }
}

TEST(CalculiX, NodalForcesAgreeNearIncompressible) {
  if (!HaveCcx()) GTEST_SKIP() << "ccx not installed (Debian package calculix-ccx)";
  const TetMesh mesh = DistortedBlock();
  CcxCase c;
  c.material = {5000.0, 0.49};
  c.fixed = NodesOnPlane(mesh, 0, 0.0);  // side clamp: a short cantilever block
  for (std::int32_t v : NodesOnPlane(mesh, 0, 0.02)) c.forces.push_back({v, {0.0, 1e-3, -2e-3}});
  c.imposed.push_back({NodesOnPlane(mesh, 2, 0.01)[10], {0, 0, -1e-4}});
  std::string detail;
  EXPECT_LT(CompareToCcx(mesh, c, &detail), 1e-5) << detail;
  RecordProperty("detail", detail);
}

}  // namespace
}  // namespace handshare::fem
