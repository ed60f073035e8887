#include "handshare/fem/static_solver.hpp"

#include <string>

#include "handshare/fem/error.hpp"
#include "reduce.hpp"

namespace handshare::fem {

std::vector<std::int32_t> UnusedNodes(const TetMesh& mesh) {
  std::vector<std::int32_t> out;
  for (std::int32_t v = 0; v < mesh.num_nodes(); ++v) {
    if (!mesh.used_nodes()[v]) out.push_back(v);
  }
  return out;
}

StaticSolver::StaticSolver(const TetMesh& mesh, const Material& material,
                           std::span<const std::int32_t> fixed_nodes,
                           std::span<const std::int32_t> imposed_nodes)
    : num_nodes_(mesh.num_nodes()), imposed_nodes_(imposed_nodes.begin(), imposed_nodes.end()) {
  material.Validate();
  // 0 = free, 1 = fixed, 2 = imposed.
  std::vector<std::uint8_t> kind(static_cast<std::size_t>(num_nodes_), 0);
  const auto node_name = [&](std::int32_t v) {
    return v >= 0 && v < num_nodes_ ? "node id " + std::to_string(mesh.node_ids()[v])
                                    : "node index " + std::to_string(v);
  };
  for (std::int32_t v : fixed_nodes) {
    if (v < 0 || v >= num_nodes_) throw InputError(mesh.source(), 0, "fixed_nodes", node_name(v) + " out of range");
    kind[v] = 1;
  }
  for (std::int32_t v : imposed_nodes) {
    if (v < 0 || v >= num_nodes_) throw InputError(mesh.source(), 0, "imposed", node_name(v) + " out of range");
    if (kind[v] == 1) throw InputError(mesh.source(), 0, "imposed", node_name(v) + " is also fixed");
    if (kind[v] == 2) throw InputError(mesh.source(), 0, "imposed", node_name(v) + " is imposed twice");
    if (!mesh.used_nodes()[v]) {
      throw InputError(mesh.source(), 0, "imposed", node_name(v) + " belongs to no element");
    }
    kind[v] = 2;
  }
  std::vector<std::int32_t> held;
  for (std::int32_t v = 0; v < num_nodes_; ++v) {
    if (kind[v] != 0) held.push_back(v);
  }
  const detail::DofMap map = detail::MakeDofMap(mesh, held);
  free_dofs_ = map.free_dofs;
  free_of_dof_ = map.free_of_dof;
  K_ = AssembleStiffness(mesh, material);
  K_ff_ = detail::FreeBlock(K_, map);
  if (K_ff_.rows() > 0) chol_.Compute(K_ff_);
}

StaticSolution StaticSolver::Solve(std::span<const Eigen::Vector3d> imposed_u_m,
                                   std::span<const NodalValue> forces_N) {
  if (imposed_u_m.size() != imposed_nodes_.size()) {
    throw InputError("", 0, "imposed", "expected " + std::to_string(imposed_nodes_.size()) +
                                           " displacements, got " + std::to_string(imposed_u_m.size()));
  }
  const std::int64_t ndof = 3 * static_cast<std::int64_t>(num_nodes_);
  Eigen::VectorXd u = Eigen::VectorXd::Zero(ndof);
  Eigen::VectorXd f = Eigen::VectorXd::Zero(ndof);
  for (std::size_t i = 0; i < imposed_nodes_.size(); ++i) {
    if (!imposed_u_m[i].allFinite()) {
      throw InputError("", 0, "imposed[" + std::to_string(i) + "].u_m", "not a finite number");
    }
    u.segment<3>(3 * imposed_nodes_[i]) = imposed_u_m[i];
  }
  for (std::size_t i = 0; i < forces_N.size(); ++i) {
    const auto& nf = forces_N[i];
    if (nf.node < 0 || nf.node >= num_nodes_) {
      throw InputError("", 0, "forces[" + std::to_string(i) + "].node", "out of range");
    }
    if (!nf.value.allFinite()) {
      throw InputError("", 0, "forces[" + std::to_string(i) + "].f_N", "not a finite number");
    }
    f.segment<3>(3 * nf.node) += nf.value;
  }
  // K_ff u_f = f_f - K_fc u_c.
  const Eigen::VectorXd Ku_c = K_ * u;  // u holds only the constrained values so far
  Eigen::VectorXd rhs(static_cast<Eigen::Index>(free_dofs_.size()));
  for (std::size_t i = 0; i < free_dofs_.size(); ++i) rhs[i] = f[free_dofs_[i]] - Ku_c[free_dofs_[i]];
  if (rhs.size() > 0) chol_.SolveInPlace(rhs);
  for (std::size_t i = 0; i < free_dofs_.size(); ++i) u[free_dofs_[i]] = rhs[i];

  const Eigen::VectorXd r = K_ * u - f;
  StaticSolution s;
  s.u_m.resize(num_nodes_);
  s.reaction_N.assign(num_nodes_, Eigen::Vector3d::Zero());
  for (std::int32_t v = 0; v < num_nodes_; ++v) {
    s.u_m[v] = u.segment<3>(3 * v);
    if (free_of_dof_[3 * v] < 0) s.reaction_N[v] = r.segment<3>(3 * v);
  }
  return s;
}

StaticSolution SolveStatic(const TetMesh& mesh, const Material& material,
                           const StaticProblem& problem) {
  std::vector<std::int32_t> imposed_nodes;
  std::vector<Eigen::Vector3d> imposed_u;
  for (const auto& iv : problem.imposed_u_m) {
    imposed_nodes.push_back(iv.node);
    imposed_u.push_back(iv.value);
  }
  StaticSolver solver(mesh, material, problem.fixed_nodes, imposed_nodes);
  return solver.Solve(imposed_u, problem.forces_N);
}

}  // namespace handshare::fem
