#pragma once
/// @file
/// The paper's form of the elementary displacement method (HIRO II chapter, eqs 6-8; Cotin et
/// al. 1999), kept beside the symmetric compliance form (ContactSolver) because it is what the
/// paper measured:
///   T^d_nk = C_nk C_kk^-1  (displacement of node n per unit elementary displacement of k; T^d_kk = I)
///   T^f_k  = C_kk^-1       (force at k per unit elementary displacement of k)
/// For touched nodes k_1..k_m with imposed d*: solve A e = d*, A_ij = T^d_{k_i k_j}
/// (the "corrected displacements" e = d~ of eq. 7), then u_n = sum_j T^d_{n k_j} e_j (eq. 7)
/// and f_j = T^f_{k_j} e_j (eq. 8). Same numbers as ContactSolver (A = C_cc D^-1, D = diag C_kk).
/// T^d is not symmetric, so it is stored in full (9 N^2 scalars), twice the compliance, by
/// touched node k in a planar layout (16 nodes' entry (r, c) side by side) so that the surface
/// sum is vertical SIMD over contiguous memory; float64, float32 or float16 (one scale per 16
/// nodes of a column: entries within ~5e-4 of the chunk's largest; the forces then carry that
/// error too, since A_ij is read from T^d. For exact forces with a float16 surface field use
/// ContactSolver + SurfaceField with SurfaceFieldLayout::kColumns instead).

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_solver.hpp"

namespace handshare::fem {

namespace detail {
class PlanarColumns;
}  // namespace detail

/// The T^d and T^f tensors of all compliance nodes. Built offline from a Compliance.
class ElementaryDisplacementTensors {
 public:
  /// Builds T^d (N x N blocks, stored by touched node k: contiguous over n) and T^f.
  /// precision: kFloat64, kFloat32 or kFloat16 of T^d (T^f is kept in float64).
  /// @throws FemError if a diagonal block C_kk is not invertible; InputError for a bad precision.
  static ElementaryDisplacementTensors FromCompliance(const Compliance& compliance,
                                                      Precision precision);

  std::int32_t num_nodes() const noexcept { return n_; }
  Precision precision() const noexcept { return precision_; }
  /// T^d_nk (slots).
  Eigen::Matrix3d Td(std::int32_t n, std::int32_t k) const noexcept;
  /// T^f_k (slot).
  Eigen::Matrix3d Tf(std::int32_t k) const noexcept;
  /// Bytes of T^d (planar, padded to 16 nodes per column) plus T^f.
  std::size_t storage_bytes() const noexcept;
  /// The planar T^d columns (internal layout, used by the solver's kernels).
  const detail::PlanarColumns& td() const noexcept { return *td_; }

  /// Slot bookkeeping copied from the compliance.
  std::int32_t SlotOf(std::int32_t mesh_node) const noexcept {
    return (mesh_node >= 0 && mesh_node < static_cast<std::int32_t>(slot_of_.size()))
               ? slot_of_[mesh_node]
               : -1;
  }
  bool IsFixed(std::int32_t mesh_node) const noexcept {
    return mesh_node >= 0 && mesh_node < static_cast<std::int32_t>(fixed_flag_.size()) &&
           fixed_flag_[mesh_node] != 0;
  }

 private:
  std::int32_t n_ = 0;
  Precision precision_ = Precision::kFloat64;
  std::shared_ptr<const detail::PlanarColumns> td_;
  std::vector<double> tf_;
  std::vector<std::int32_t> slot_of_;
  std::vector<std::uint8_t> fixed_flag_;
};

/// Real-time solver in the paper's form. Always imposes all three components (the paper's
/// elementary displacements); ContactInput::mode and n_out are ignored. Merges repeated nodes and
/// rejects fixed and unknown ones like ContactSolver. noexcept, no allocation after construction.
class ElementaryDisplacementSolver {
 public:
  ElementaryDisplacementSolver(std::shared_ptr<const ElementaryDisplacementTensors> tensors,
                               std::int32_t max_contacts);

  /// Solve A e = d* (3m x 3m LU with partial pivoting), then f_j = T^f e_j.
  StepStatus Solve(std::span<const ContactInput> contacts) noexcept;
  /// Force on the object per input contact [N] (same conventions as ContactSolver).
  std::span<const Eigen::Vector3d> forces_N() const noexcept {
    return {forces_N_.data(), static_cast<std::size_t>(num_inputs_)};
  }
  std::span<const ContactState> states() const noexcept {
    return {states_.data(), static_cast<std::size_t>(num_inputs_)};
  }
  /// u_n = sum_j T^d_{n k_j} e_j for every slot. u_m.size() must be num_nodes().
  bool SurfaceDisplacements(std::span<Eigen::Vector3d> u_m) const noexcept;

 private:
  std::shared_ptr<const ElementaryDisplacementTensors> t_;
  std::int32_t max_contacts_ = 0;
  std::int32_t num_inputs_ = 0;
  std::int32_t num_unique_ = 0;
  std::vector<Eigen::Vector3d> forces_N_;
  std::vector<ContactState> states_;
  std::vector<std::int32_t> unique_of_input_;
  std::vector<std::int32_t> slot_;
  std::vector<std::int32_t> multiplicity_;
  std::vector<Eigen::Vector3d> d_m_;
  std::vector<Eigen::Vector3d> e_m_;
  std::vector<double> A_;
  std::vector<double> rhs_;
  std::vector<std::int32_t> piv_;
};

}  // namespace handshare::fem
