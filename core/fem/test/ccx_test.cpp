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

struct CcxCase {
  Material material;
  std::vector<std::int32_t> fixed;
  std::vector<NodalValue> imposed;
  std::vector<NodalValue> forces;
};

void WriteInp(const std::filesystem::path& file, const TetMesh& mesh, const CcxCase& c) {
  std::ofstream o(file);
  const auto& id = mesh.node_ids();
  o << "*NODE, NSET=NALL\n";
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    const auto& x = mesh.positions_m()[v];
    o << id[v] << ", " << G12(x.x()) << ", " << G12(x.y()) << ", " << G12(x.z()) << "\n";
  }
  o << "*ELEMENT, TYPE=C3D4, ELSET=EALL\n";
  for (std::int32_t e = 0; e < mesh.num_tets(); ++e) {
    const auto& t = mesh.tets()[e];
    o << e + 1 << ", " << id[t[0]] << ", " << id[t[1]] << ", " << id[t[2]] << ", " << id[t[3]] << "\n";
  }
  o << "*NSET, NSET=NFIX\n";
  for (std::int32_t v : c.fixed) o << id[v] << ",\n";
  o << "*NSET, NSET=NIMP\n";
  for (const auto& iv : c.imposed) o << id[iv.node] << ",\n";
  o << "*MATERIAL, NAME=MAT\n*ELASTIC\n" << G12(c.material.E_Pa) << ", " << G12(c.material.nu) << "\n";
  o << "*SOLID SECTION, ELSET=EALL, MATERIAL=MAT\n*STEP\n*STATIC\n*BOUNDARY\nNFIX, 1, 3\n";
  for (const auto& iv : c.imposed)
    for (int a = 0; a < 3; ++a) o << id[iv.node] << ", " << a + 1 << ", " << a + 1 << ", " << G12(iv.value[a]) << "\n";
  if (!c.forces.empty()) {
    o << "*CLOAD\n";
    for (const auto& f : c.forces)
      for (int a = 0; a < 3; ++a) o << id[f.node] << ", " << a + 1 << ", " << G12(f.value[a]) << "\n";
  }
  o << "*NODE PRINT, NSET=NALL\nU\n";
  if (!c.imposed.empty()) o << "*NODE PRINT, NSET=NIMP\nRF\n";
  o << "*END STEP\n";
}

// Reads the "displacements" and "forces" tables of job.dat: id -> vector.
std::map<std::string, std::map<std::int64_t, Eigen::Vector3d>> ReadDat(const std::filesystem::path& file) {
  std::map<std::string, std::map<std::int64_t, Eigen::Vector3d>> tables;
  std::ifstream in(file);
  std::string line, table;
  while (std::getline(in, line)) {
    if (line.find("displacements (vx,vy,vz)") != std::string::npos) {
      table = "U";
      continue;
    }
    if (line.find("forces (fx,fy,fz)") != std::string::npos) {
      table = "RF";
      continue;
    }
    std::istringstream ss(line);
    std::int64_t id;
    Eigen::Vector3d v;
    if (!table.empty() && (ss >> id >> v.x() >> v.y() >> v.z())) tables[table][id] = v;
  }
  return tables;
}

// Runs ccx on the case in a scratch folder; returns the tables of job.dat.
std::map<std::string, std::map<std::int64_t, Eigen::Vector3d>> RunCcx(const TetMesh& mesh, const CcxCase& c,
                                                                   const test::TempDir& dir) {
  WriteInp(dir.path() / "job.inp", mesh, c);
  const std::string cmd = "cd '" + dir.path().string() + "' && OMP_NUM_THREADS=1 ccx -i job > ccx.log 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << "ccx failed, see " << dir.path() / "ccx.log";
  auto tables = ReadDat(dir.path() / "job.dat");
  EXPECT_EQ(tables["U"].size(), static_cast<std::size_t>(mesh.num_nodes()));
  return tables;
}

double CompareToCcx(const TetMesh& mesh, const CcxCase& c, std::string* detail) {
  test::TempDir dir;
  auto tables = RunCcx(mesh, c, dir);
  // Our solver on the mesh as written (12 digits) and re-read.
  const TetMesh ours_mesh = ReadAbaqusInp(dir.path() / "job.inp");
  EXPECT_EQ(ours_mesh.num_nodes(), mesh.num_nodes());
  auto remap = [&](std::int32_t v) { return *ours_mesh.IndexOfId(mesh.node_ids()[v]); };
  StaticProblem p;
  for (std::int32_t v : c.fixed) p.fixed_nodes.push_back(remap(v));
  for (const auto& iv : c.imposed) p.imposed_u_m.push_back({remap(iv.node), iv.value});
  for (const auto& f : c.forces) p.forces_N.push_back({remap(f.node), f.value});
  const Material m{std::stod(G12(c.material.E_Pa)), std::stod(G12(c.material.nu))};
  const StaticSolution s = SolveStatic(ours_mesh, m, p);

  std::vector<Eigen::Vector3d> a, b, ra, rb;
  for (std::int32_t v = 0; v < ours_mesh.num_nodes(); ++v) {
    a.push_back(s.u_m[v]);
    b.push_back(tables["U"][ours_mesh.node_ids()[v]]);
  }
  for (const auto& iv : p.imposed_u_m) {
    ra.push_back(s.reaction_N[iv.node]);
    rb.push_back(tables["RF"][ours_mesh.node_ids()[iv.node]]);
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
    for (const auto& iv : c.imposed) ccx_f.push_back(tables["RF"][mesh.node_ids()[iv.node]]);
    std::vector<Eigen::Vector3d> field(static_cast<std::size_t>(C->num_nodes()));
    ASSERT_TRUE(solver.SurfaceDisplacements(field));
    for (std::int32_t k = 0; k < C->num_nodes(); ++k) {
      ours_u.push_back(field[static_cast<std::size_t>(k)]);
      ccx_u.push_back(tables["U"][mesh.node_ids()[C->nodes()[k]]]);
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
