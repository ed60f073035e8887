#include "handshare/fem/elementary_displacement.hpp"

#include <string>

#include <Eigen/LU>

#include "dense_small.hpp"
#include "handshare/fem/error.hpp"
#include "merge_contacts.hpp"
#include "planar_columns.hpp"

namespace handshare::fem {
ElementaryDisplacementTensors ElementaryDisplacementTensors::FromCompliance(
    const Compliance& C, Precision precision) {
  ElementaryDisplacementTensors t;
  t.n_ = C.num_nodes();
  t.precision_ = precision;
  detail::PlanarType type = detail::PlanarType::kFloat64;
  switch (precision) {
    case Precision::kFloat64: type = detail::PlanarType::kFloat64; break;
    case Precision::kFloat32: type = detail::PlanarType::kFloat32; break;
    case Precision::kFloat16: type = detail::PlanarType::kFloat16; break;
    default: throw InputError("", 0, "precision", "must be float16, float32 or float64");
  }
  t.tf_.resize(9 * static_cast<std::size_t>(t.n_));
  for (std::int32_t k = 0; k < t.n_; ++k) {
    // T^f_k = C_kk^-1: the force at k per unit elementary displacement of k (paper eq. 8).
    const Eigen::Matrix3d Ckk = C.Block(k, k);
    Eigen::FullPivLU<Eigen::Matrix3d> lu(Ckk);
    if (!lu.isInvertible()) {
      throw FemError("elementary displacement: C_kk of slot " + std::to_string(k) + " is singular");
    }
    Eigen::Map<Eigen::Matrix3d>(t.tf_.data() + 9 * static_cast<std::size_t>(k)) = lu.inverse();
  }
  // T^d_nk = C_nk C_kk^-1 (paper eq. 6: displacement of n per unit displacement of k); T^d_kk = I.
  auto td = std::make_shared<detail::PlanarColumns>();
  td->Build(t.n_, t.n_, type, [&](std::int32_t n, std::int32_t k) -> Eigen::Matrix3d {
    if (n == k) return Eigen::Matrix3d::Identity();
    return C.Block(n, k) * Eigen::Map<const Eigen::Matrix3d>(t.tf_.data() + 9 * static_cast<std::size_t>(k));
  });
  t.td_ = std::move(td);
  t.slot_of_.resize(static_cast<std::size_t>(C.num_mesh_nodes()));
  t.fixed_flag_.resize(static_cast<std::size_t>(C.num_mesh_nodes()));
  for (std::int32_t v = 0; v < C.num_mesh_nodes(); ++v) {
    t.slot_of_[v] = C.SlotOf(v);
    t.fixed_flag_[v] = C.IsFixed(v) ? 1 : 0;
  }
  return t;
}

Eigen::Matrix3d ElementaryDisplacementTensors::Td(std::int32_t n, std::int32_t k) const noexcept {
  return td_->Get(n, k);
}

std::size_t ElementaryDisplacementTensors::storage_bytes() const noexcept {
  return (td_ ? td_->storage_bytes() : 0) + tf_.size() * sizeof(double);
}

Eigen::Matrix3d ElementaryDisplacementTensors::Tf(std::int32_t k) const noexcept {
  return Eigen::Map<const Eigen::Matrix3d>(tf_.data() + 9 * static_cast<std::size_t>(k));
}

ElementaryDisplacementSolver::ElementaryDisplacementSolver(
    std::shared_ptr<const ElementaryDisplacementTensors> tensors, std::int32_t max_contacts)
    : t_(std::move(tensors)), max_contacts_(max_contacts) {
  if (!t_) throw InputError("", 0, "tensors", "null");
  if (max_contacts < 1 || max_contacts > 1024) {
    throw InputError("", 0, "max_contacts", "must be in 1..1024");
  }
  const auto M = static_cast<std::size_t>(max_contacts);
  forces_N_.assign(M, Eigen::Vector3d::Zero());
  states_.assign(M, ContactState::kActive);
  unique_of_input_.assign(M, -1);
  slot_.assign(M, -1);
  multiplicity_.assign(M, 0);
  d_m_.assign(M, Eigen::Vector3d::Zero());
  e_m_.assign(M, Eigen::Vector3d::Zero());
  A_.assign(9 * M * M, 0.0);
  rhs_.assign(3 * M, 0.0);
  piv_.assign(3 * M, 0);
}

StepStatus ElementaryDisplacementSolver::Solve(std::span<const ContactInput> contacts) noexcept {
  const bool overflow = contacts.size() > static_cast<std::size_t>(max_contacts_);
  num_inputs_ = overflow ? max_contacts_ : static_cast<std::int32_t>(contacts.size());
  num_unique_ = 0;
  bool rejected = overflow;
  for (std::int32_t i = 0; i < num_inputs_; ++i) {
    const ContactInput& c = contacts[i];
    forces_N_[i].setZero();
    unique_of_input_[i] = -1;
    if (!c.u_m.allFinite()) {
      for (std::int32_t j = 0; j < num_unique_; ++j) e_m_[j].setZero();
      for (std::int32_t q = 0; q < num_inputs_; ++q) forces_N_[q].setZero();
      num_unique_ = 0;
      return StepStatus::kInvalidInput;
    }
    if (t_->IsFixed(c.node)) {
      states_[i] = ContactState::kRejectedFixed;
      rejected = true;
      continue;
    }
    const std::int32_t slot = t_->SlotOf(c.node);
    if (slot < 0) {
      states_[i] = ContactState::kRejectedUnknownNode;
      rejected = true;
      continue;
    }
    const std::int32_t j =
        detail::MergeTouch(slot, c.u_m, slot_.data(), multiplicity_.data(), d_m_.data(), num_unique_);
    unique_of_input_[i] = j;
    states_[i] = ContactState::kActive;
  }
  if (num_unique_ == 0) return rejected ? StepStatus::kSomeRejected : StepStatus::kOk;

  // A_ij = T^d_{k_i k_j}: the displacement of touched node k_i per unit elementary displacement
  // of k_j. Solving A e = d* is Cotin's correction: e are the elementary displacements whose
  // superposition (eq. 7) puts every touched node exactly at d*.
  const int ld = 3 * max_contacts_;
  const int n = 3 * num_unique_;
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    d_m_[j] /= static_cast<double>(multiplicity_[j]);
    for (std::int32_t i = 0; i < num_unique_; ++i) {
      const Eigen::Matrix3d T = t_->Td(slot_[i], slot_[j]);
      double* a = A_.data() + static_cast<std::ptrdiff_t>(3 * j) * ld + 3 * i;
      for (int c = 0; c < 3; ++c)
        for (int r = 0; r < 3; ++r) a[c * ld + r] = T(r, c);
    }
    for (int c = 0; c < 3; ++c) rhs_[3 * j + c] = d_m_[j][c];
  }
  if (!detail::LuInPlace(A_.data(), n, ld, piv_.data())) {
    for (std::int32_t j = 0; j < num_unique_; ++j) e_m_[j].setZero();
    num_unique_ = 0;
    return StepStatus::kNumericalFailure;
  }
  detail::LuSolveInPlace(A_.data(), n, ld, piv_.data(), rhs_.data());
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    e_m_[j] = Eigen::Vector3d(rhs_[3 * j], rhs_[3 * j + 1], rhs_[3 * j + 2]);
  }
  // f_j = T^f_{k_j} e_j (eq. 8), split evenly over merged inputs.
  for (std::int32_t i = 0; i < num_inputs_; ++i) {
    const std::int32_t j = unique_of_input_[i];
    if (j < 0) continue;
    forces_N_[i] = t_->Tf(slot_[j]) * e_m_[j] / static_cast<double>(multiplicity_[j]);
  }
  return rejected ? StepStatus::kSomeRejected : StepStatus::kOk;
}

bool ElementaryDisplacementSolver::SurfaceDisplacements(
    std::span<Eigen::Vector3d> u_m) const noexcept {
  const std::int32_t N = t_->num_nodes();
  if (u_m.size() != static_cast<std::size_t>(N)) return false;
  // u_n = sum_j T^d_{n k_j} e_j (eq. 7): T^d is stored by touched node, so each term streams.
  t_->td().SumColumns(std::span<const std::int32_t>(slot_.data(), static_cast<std::size_t>(num_unique_)),
                      std::span<const Eigen::Vector3d>(e_m_.data(), static_cast<std::size_t>(num_unique_)),
                      u_m.data(), detail::BestIsa());
  return true;
}

}  // namespace handshare::fem
