#pragma once
/// @file
/// Direct static solve K u = f with fixed and imposed nodal displacements (CHOLMOD). The
/// reference the real-time solvers are measured against, and the engine of `fem_solve`.
/// Offline only.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include "handshare/fem/assembly.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/fem/sparse_cholesky.hpp"

namespace handshare::fem {

/// A nodal vector value: node index (into the mesh) and a 3-vector.
struct NodalValue {
  std::int32_t node = 0;
  Eigen::Vector3d value = Eigen::Vector3d::Zero();
};

/// Boundary conditions and loads of one static problem.
struct StaticProblem {
  std::vector<std::int32_t> fixed_nodes;  ///< held at u = 0.
  std::vector<NodalValue> imposed_u_m;    ///< imposed displacement [m] (all 3 components).
  std::vector<NodalValue> forces_N;       ///< external nodal forces [N] on free nodes.
};

/// Result of a static solve, one entry per mesh node.
struct StaticSolution {
  std::vector<Eigen::Vector3d> u_m;         ///< displacement [m].
  std::vector<Eigen::Vector3d> reaction_N;  ///< K u - f at constrained nodes [N]; 0 elsewhere.
};

/// Factors K_ff once for a given set of constrained nodes, then solves for any imposed values.
/// Nodes that belong to no element are held at zero (they have no stiffness).
class StaticSolver {
 public:
  /// @param fixed_nodes    nodes held at zero.
  /// @param imposed_nodes  nodes whose displacement Solve() imposes (distinct, not fixed).
  /// @throws InputError for out-of-range, repeated or fixed-and-imposed nodes;
  ///         FemError if K_ff is singular (an object that is not held).
  StaticSolver(const TetMesh& mesh, const Material& material,
               std::span<const std::int32_t> fixed_nodes,
               std::span<const std::int32_t> imposed_nodes);

  /// @param imposed_u_m  one displacement [m] per imposed node, same order as the constructor's.
  /// @param forces_N     external nodal forces [N]; forces on constrained nodes are allowed and
  ///                     show up in the reactions.
  StaticSolution Solve(std::span<const Eigen::Vector3d> imposed_u_m,
                       std::span<const NodalValue> forces_N = {});

  const Eigen::SparseMatrix<double>& stiffness() const noexcept { return K_; }
  /// Number of free DOFs (size of K_ff).
  std::int64_t num_free_dofs() const noexcept { return static_cast<std::int64_t>(free_dofs_.size()); }
  SparseCholesky& factor() noexcept { return chol_; }

 private:
  std::int32_t num_nodes_ = 0;
  Eigen::SparseMatrix<double> K_;
  Eigen::SparseMatrix<double> K_ff_;
  std::vector<std::int64_t> free_dofs_;    // free index -> global DOF
  std::vector<std::int64_t> free_of_dof_;  // global DOF -> free index or -1
  std::vector<std::int32_t> imposed_nodes_;
  SparseCholesky chol_;
};

/// One-shot convenience: StaticSolver + Solve.
StaticSolution SolveStatic(const TetMesh& mesh, const Material& material,
                           const StaticProblem& problem);

/// Nodes used by no element (no stiffness; the solvers hold them at zero).
std::vector<std::int32_t> UnusedNodes(const TetMesh& mesh);

}  // namespace handshare::fem
