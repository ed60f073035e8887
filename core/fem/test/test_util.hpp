#pragma once
// Helpers shared by the FEM tests: procedural meshes, temporary files, error norms, the direct
// reference solve of a contact set.

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <fstream>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/fem/static_solver.hpp"

namespace handshare::fem::test {

// A temporary directory, removed at scope exit.
class TempDir {
 public:
  TempDir() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "handshare-fem-test-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) std::abort();
    path_ = tmpl;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path Write(const std::string& name, const std::string& text) const {
    const auto p = path_ / name;
    std::ofstream(p, std::ios::binary) << text;
    return p;
  }

 private:
  std::filesystem::path path_;
};

// A box [0,L]^3-ish block with its bottom face (z = 0) fixed.
struct Block {
  TetMesh mesh;
  std::vector<std::int32_t> fixed;
};

inline Block MakeFixedBottomBox(const Eigen::Vector3d& size_m, const std::array<int, 3>& cells) {
  Block b{MakeBoxMesh(size_m, cells), {}};
  b.fixed = NodesOnPlane(b.mesh, 2, 0.0, 1e-12);
  return b;
}

// Coordinates from 0 to `extent_m`: spacing h_m up to `fine_m`, then growing by `growth` per cell
// (graded meshes keep the fine region small and the far boundary far).
inline std::vector<double> GradedAxis(double fine_m, double h_m, double extent_m, double growth) {
  std::vector<double> x = {0.0};
  double step = h_m;
  while (x.back() < extent_m - 1e-12 * extent_m) {
    if (x.back() >= fine_m - 1e-12 * fine_m) step *= growth;
    double next = x.back() + step;
    // Do not leave a sliver of a last cell.
    if (next > extent_m - 0.5 * step) next = extent_m;
    x.push_back(next);
  }
  return x;
}

// The same, mirrored about 0: -extent .. extent.
inline std::vector<double> SymmetricGradedAxis(double fine_m, double h_m, double extent_m, double growth) {
  const std::vector<double> half = GradedAxis(fine_m, h_m, extent_m, growth);
  std::vector<double> x;
  for (auto it = half.rbegin(); it != half.rend(); ++it) x.push_back(-*it);
  x.insert(x.end(), half.begin() + 1, half.end());
  return x;
}

// "1.234e-05": for RecordProperty and messages.
inline std::string Sci(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.3e", v);
  return b;
}

// ||a - b|| / ||b|| over stacked 3-vectors.
inline double RelError(const std::vector<Eigen::Vector3d>& a, const std::vector<Eigen::Vector3d>& b) {
  double num = 0.0, den = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    num += (a[i] - b[i]).squaredNorm();
    den += b[i].squaredNorm();
  }
  return den > 0.0 ? std::sqrt(num / den) : std::sqrt(num);
}

// The exact static FEM answer for a set of touched nodes held at u (direct sparse solve):
// contact forces are the reactions at the touched nodes.
struct DirectContact {
  std::vector<Eigen::Vector3d> forces_N;  // per contact
  StaticSolution solution;
};

inline DirectContact SolveDirect(const TetMesh& mesh, const Material& mat,
                                 const std::vector<std::int32_t>& fixed,
                                 const std::vector<ContactInput>& contacts) {
  std::vector<std::int32_t> nodes;
  std::vector<Eigen::Vector3d> u;
  for (const auto& c : contacts) {
    nodes.push_back(c.node);
    u.push_back(c.u_m);
  }
  StaticSolver solver(mesh, mat, fixed, nodes);
  DirectContact d;
  d.solution = solver.Solve(u);
  for (const auto& c : contacts) d.forces_N.push_back(d.solution.reaction_N[c.node]);
  return d;
}

// m distinct random compliance nodes with random displacements of up to 1 mm.
inline std::vector<ContactInput> RandomContacts(const Compliance& c, int m, std::mt19937& rng) {
  std::uniform_int_distribution<std::int32_t> slot(0, c.num_nodes() - 1);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  std::vector<ContactInput> out;
  while (static_cast<int>(out.size()) < m) {
    const std::int32_t node = c.nodes()[slot(rng)];
    bool dup = false;
    for (const auto& x : out) dup = dup || x.node == node;
    if (dup) continue;
    ContactInput ci;
    ci.node = node;
    ci.u_m = {u(rng), u(rng), u(rng)};
    out.push_back(ci);
  }
  return out;
}

// A block and its float64 compliance.
struct BlockModel {
  Block block;
  std::shared_ptr<const Compliance> c64;
};

inline BlockModel MakeBlockModel(Block b, const Material& m) {
  BlockModel r{std::move(b), nullptr};
  r.c64 = std::make_shared<Compliance>(Compliance::Precompute(r.block.mesh, m, r.block.fixed, {}));
  return r;
}

// An upper bound on the largest eigenvalue of the mesh's stiffness matrix (Gershgorin, +1%): no
// contact solve can ask more force per metre of imposed displacement.
inline double StiffnessEigenBound(const TetMesh& mesh, const Material& m) {
  const auto K = AssembleStiffness(mesh, m);
  Eigen::VectorXd row_sum = Eigen::VectorXd::Zero(K.rows());
  for (int k = 0; k < K.outerSize(); ++k)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, k); it; ++it) row_sum[it.row()] += std::abs(it.value());
  return row_sum.maxCoeff() * 1.01;
}

}  // namespace handshare::fem::test
