#include "handshare/fem/assembly.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/LU>

#include "handshare/fem/error.hpp"

namespace handshare::fem {

void Material::Validate() const {
  if (!std::isfinite(E_Pa) || !(E_Pa > 0.0)) {
    throw InputError("", 0, "E_Pa", "Young's modulus must be a positive finite number, got " +
                                        std::to_string(E_Pa));
  }
  if (!std::isfinite(nu) || !(nu > -1.0) || !(nu < 0.5)) {
    throw InputError("", 0, "nu",
                     "Poisson's ratio must satisfy -1 < nu < 0.5, got " + std::to_string(nu));
  }
}

Eigen::Matrix<double, 12, 12> TetStiffness(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                           const Eigen::Vector3d& p2, const Eigen::Vector3d& p3,
                                           const Material& m) {
  // Shape function gradients: with J = [p1-p0, p2-p0, p3-p0], grad N_i = J^-T e_i (i = 1..3)
  // and grad N_0 = -(sum of the others). Constant strain, so K_e = V B^T D B exactly; written
  // per node pair: K_ab = V (lambda g_a g_b^T + mu g_b g_a^T + mu (g_a . g_b) I).
  Eigen::Matrix3d J;
  J.col(0) = p1 - p0;
  J.col(1) = p2 - p0;
  J.col(2) = p3 - p0;
  const double V = J.determinant() / 6.0;
  const Eigen::Matrix3d JinvT = J.inverse().transpose();
  Eigen::Matrix<double, 3, 4> g;
  g.rightCols<3>() = JinvT;
  g.col(0) = -JinvT.rowwise().sum();
  const double lambda = m.lambda_Pa();
  const double mu = m.G_Pa();
  Eigen::Matrix<double, 12, 12> K;
  for (int a = 0; a < 4; ++a) {
    for (int b = 0; b < 4; ++b) {
      const Eigen::Vector3d ga = g.col(a);
      const Eigen::Vector3d gb = g.col(b);
      K.block<3, 3>(3 * a, 3 * b) =
          V * (lambda * ga * gb.transpose() + mu * gb * ga.transpose() +
               mu * ga.dot(gb) * Eigen::Matrix3d::Identity());
    }
  }
  return K;
}

Eigen::SparseMatrix<double> AssembleStiffness(const TetMesh& mesh, const Material& material) {
  material.Validate();
  const std::int32_t n = mesh.num_nodes();
  // Node graph: neighbours (including self) of each node, sorted. The DOF pattern is this graph
  // with every entry expanded to a 3x3 block, so columns are built directly (no triplets: a
  // 90k-DOF mesh would need ~10^8 of them).
  std::vector<std::vector<std::int32_t>> adj(n);
  for (const Tet& t : mesh.tets()) {
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) adj[t[a]].push_back(t[b]);
  }
  for (auto& a : adj) {
    std::sort(a.begin(), a.end());
    a.erase(std::unique(a.begin(), a.end()), a.end());
  }
  const std::int64_t ndof = 3 * static_cast<std::int64_t>(n);
  std::vector<std::int64_t> col_start(ndof + 1, 0);
  for (std::int32_t j = 0; j < n; ++j) {
    for (int c = 0; c < 3; ++c) col_start[3 * j + c + 1] = 3 * static_cast<std::int64_t>(adj[j].size());
  }
  for (std::int64_t c = 0; c < ndof; ++c) col_start[c + 1] += col_start[c];
  const std::int64_t nnz = col_start[ndof];
  if (nnz > INT32_MAX) throw FemError("stiffness matrix too large for 32-bit indices");

  Eigen::SparseMatrix<double> K(ndof, ndof);
  K.resizeNonZeros(nnz);
  int* outer = K.outerIndexPtr();
  int* inner = K.innerIndexPtr();
  double* val = K.valuePtr();
  for (std::int64_t c = 0; c <= ndof; ++c) outer[c] = static_cast<int>(col_start[c]);
  for (std::int32_t j = 0; j < n; ++j) {
    for (int c = 0; c < 3; ++c) {
      std::int64_t pos = col_start[3 * j + c];
      for (std::int32_t i : adj[j])
        for (int r = 0; r < 3; ++r) {
          inner[pos] = 3 * i + r;
          val[pos] = 0.0;
          ++pos;
        }
    }
  }
  const auto& p = mesh.positions_m();
  for (const Tet& t : mesh.tets()) {
    const auto Ke = TetStiffness(p[t[0]], p[t[1]], p[t[2]], p[t[3]], material);
    for (int b = 0; b < 4; ++b) {
      const auto& nb = adj[t[b]];
      for (int a = 0; a < 4; ++a) {
        // Row block of node t[a] inside the columns of node t[b].
        const auto k = std::lower_bound(nb.begin(), nb.end(), t[a]) - nb.begin();
        for (int cb = 0; cb < 3; ++cb) {
          double* col = val + col_start[3 * t[b] + cb] + 3 * k;
          for (int ra = 0; ra < 3; ++ra) col[ra] += Ke(3 * a + ra, 3 * b + cb);
        }
      }
    }
  }
  return K;
}

}  // namespace handshare::fem
