#pragma once
// Internal: the free-DOF reduction shared by the static solver and the precomputation.

#include <cstdint>
#include <span>
#include <vector>

#include <Eigen/SparseCore>

#include "handshare/fem/mesh.hpp"

namespace handshare::fem::detail {

// DOF partition: free_of_dof[d] = index among free DOFs, or -1 (constrained).
struct DofMap {
  std::vector<std::int64_t> free_of_dof;
  std::vector<std::int64_t> free_dofs;
};

// Constrained nodes: `held` (fixed, imposed) plus nodes in no element (no stiffness).
DofMap MakeDofMap(const TetMesh& mesh, std::span<const std::int32_t> held);

// K_ff: rows and columns of the free DOFs, compressed.
Eigen::SparseMatrix<double> FreeBlock(const Eigen::SparseMatrix<double>& K, const DofMap& map);

}  // namespace handshare::fem::detail
