#include "handshare/fem/contact_solver.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include <algorithm>
#include <cstring>
#include <cmath>
#include <limits>
#include <string>

#include "dense_spd.hpp"
#include "dense_small.hpp"
#include "handshare/fem/error.hpp"
#include "kernels.hpp"
#include "merge_contacts.hpp"
#include "small_spd_solve.hpp"

namespace handshare::fem {

namespace {

// SolveWithPatches: a fingertip that moved less than this along the surface this step is at
// rest: 1 mm/s at 1 kHz, where a stroke is 10-100 um a step and a device's noise well under 1 um.
constexpr double kRestMotion_m = 1e-6;
// Kinetic friction on nodes held along their normal (KineticDirection): a patch that slipped in
// the previous step keeps sliding the way its fingertip moves while that is more than this a
// step (a slow stroke's smoothed motion dips under kRestMotion_m); any other needs kRestMotion_m.
constexpr double kKineticRestMotion_m = 1e-7;
// Most rounds that only turn the slipping patches' directions since the held set last changed,
// and most updates of the given forces.
constexpr std::int32_t kMaxDirectionRounds = 16;
constexpr std::int32_t kMaxForceUpdates = 100;

// Relative tolerance of the active-set tests: a held node pulls, or a released one is pressed
// into its tip, by more than this share of the largest force or imposed displacement.
constexpr double kTol = 1e-9;

// The active-set pivoting rule of both solve paths: flip every violating contact at once (block
// principal pivoting) while the number of violations keeps falling, with 3 tries of grace, else
// one contact, the least index (Murty's rule, which cannot cycle).
class BlockPivoting {
 public:
  explicit BlockPivoting(std::int32_t contacts) noexcept : best_violations_(contacts + 1) {}
  /// True: flip every violating contact this iteration; false: only the first.
  bool Block(std::int32_t violations) noexcept {
    if (violations < best_violations_) {
      best_violations_ = violations;
      grace_ = 3;
      return true;
    }
    if (grace_ > 0) {
      --grace_;
      return true;
    }
    return false;
  }

 private:
  std::int32_t best_violations_;
  int grace_ = 3;
};

// The held systems of the 3-D paths (3 rows per node held in 3-D: 40-60 rows for five fingertip
// patches) are factored and solved in place in the caller's buffer (column-major, leading
// dimension ld) by dense_spd.hpp: an AVX-512 factor where the processor has it, else Eigen's
// blocked one, and Eigen's solves (the scalar loops of dense_small.hpp read the factor's rows
// with stride ld and were most of a friction step). Neither touches the heap.
bool FactorSpd(double* A, int n, int ld) noexcept { return detail::FactorSpd(A, n, ld, detail::BestIsa()); }

void SolveFactored(const double* L, int n, int ld, double* B, int nrhs, int ldb) noexcept {
  detail::SolveFactoredSpd(L, n, ld, B, nrhs, ldb, detail::BestIsa());
}

}  // namespace

ContactSolver::ContactSolver(std::shared_ptr<const Compliance> compliance,
                             const ContactSolverOptions& options)
    : compliance_(compliance), options_(options), field_(compliance) {
  CheckOptions();
  eps_m_per_N_ = options_.regularization_m_per_N;
  if (options_.coupling_stiffness_N_per_m > 0.0) eps_m_per_N_ += 1.0 / options_.coupling_stiffness_N_per_m;
  AllocateContactBuffers();
  AllocatePatchBuffers();
}

void ContactSolver::CheckOptions() const {
  if (!compliance_) throw InputError("", 0, "compliance", "null");
  if (compliance_->num_nodes() == 0) throw InputError("", 0, "compliance", "empty");
  if (options_.max_contacts < 1 || options_.max_contacts > 1024) {
    throw InputError("", 0, "max_contacts", "must be in 1..1024, got " + std::to_string(options_.max_contacts));
  }
  if (!std::isfinite(options_.regularization_m_per_N) || options_.regularization_m_per_N < 0.0) {
    throw InputError("", 0, "regularization_m_per_N", "must be finite and >= 0");
  }
  if (!std::isfinite(options_.coupling_stiffness_N_per_m) || options_.coupling_stiffness_N_per_m < 0.0) {
    throw InputError("", 0, "coupling_stiffness_N_per_m", "must be finite and >= 0 (0 = off)");
  }
  if (options_.max_active_set_iterations < 0) {
    throw InputError("", 0, "max_active_set_iterations", "must be >= 0");
  }
  if (options_.max_friction_patches < 0 || options_.max_friction_patches > 1024) {
    throw InputError("", 0, "max_friction_patches",
                     "must be in 0..1024, got " + std::to_string(options_.max_friction_patches));
  }
}

void ContactSolver::AllocateContactBuffers() {
  const auto M = static_cast<std::size_t>(options_.max_contacts);
  forces_N_.assign(M, Eigen::Vector3d::Zero());
  states_.assign(M, ContactState::kActive);
  unique_of_input_.assign(M, -1);
  slot_.assign(M, -1);
  multiplicity_.assign(M, 0);
  d_m_.assign(M, Eigen::Vector3d::Zero());
  n_.assign(M, Eigen::Vector3d::Zero());
  mode_.assign(M, ContactMode::kFull3d);
  mode_in_.assign(M, ContactMode::kFull3d);
  frozen_.assign(M, 0);
  active_.assign(M, 0);
  slipping_.assign(M, 0);
  f_N_.assign(M, Eigen::Vector3d::Zero());
  u_c_m_.assign(M, Eigen::Vector3d::Zero());
  Ccc_.assign(9 * M * M, 0.0);
  prev_index_.assign(M, -1);
  prev_pos_.assign(M, -1);
  prev_kept_.assign(M, 0);
  pos_.assign(M, -1);
  is_new_.assign(M, 0);
  free_pos_.assign(M, 0);
  table_.assign(9 * M * (M + 1) / 2, 0.0);
  pos_n_.assign(M, Eigen::Vector3d::Zero());
  same_n_.assign(M, 0);
  A_.assign(9 * M * M, 0.0);
  rhs_.assign(3 * M, 0.0);
  row_of_.assign(M, -1);
  loads_.assign(M, NodeLoad{});
  S_.assign(M * M, 0.0);
  L_.assign(M * M, 0.0);
  lambda_N_.assign(M, 0.0);
  dn_m_.assign(M, 0.0);
  act_.assign(M, -1);
  act_pos_.assign(M, -1);
  index_of_slot_.assign(static_cast<std::size_t>(compliance_->num_nodes()), -1);
  prev_of_slot_.assign(static_cast<std::size_t>(compliance_->num_nodes()), -1);
  violates_.assign(M, 0);
  prev_slot_.assign(M, -1);
  prev_active_.assign(M, 0);
  perm_.assign(M, 0);
  perm_scratch_.assign(M, 0);
  in_perm_.assign(M, 0);
  fac_slot_.assign(M, -1);
  fac_full3d_.assign(M, 0);
  fac_n_.assign(M, Eigen::Vector3d::Zero());
}

void ContactSolver::AllocatePatchBuffers() {
  const auto M = static_cast<std::size_t>(options_.max_contacts);
  const auto P = static_cast<std::size_t>(options_.max_friction_patches);
  patch_of_.assign(M, -1);
  releases_.assign(M, 0);
  slip_force_.assign(P, Eigen::Vector2d::Zero());
  warm_slip_.assign(P, 0);
  settles_.assign(P, 0);
  restuck_.assign(P, 0);
  patch_in_.assign(P, FrictionPatch{});
  tangent_.assign(P, Eigen::Matrix<double, 3, 2>::Zero());
  slip_dir_.assign(P, Eigen::Vector2d::Zero());
  patch_state_.assign(P, FrictionPatchState{});
  slipping_list_.assign(P, -1);
  // Kinetic nodes: two per patch at most (a fingertip on a stiff spine holds one or two nodes;
  // beyond that a node that pulls keeps no friction, as before).
  max_kinetic_ = static_cast<std::int32_t>(std::min(M, 2 * P));
  const auto K = static_cast<std::size_t>(max_kinetic_);
  const std::size_t unknowns = 2 * P + 2 * K;  // slides and kinetic loads
  Z_.assign(3 * M * (unknowns + 1), 0.0);
  slip_M_.assign(unknowns * unknowns, 0.0);
  slip_rhs_.assign(unknowns, 0.0);
  slip_piv_.assign(unknowns, 0);
  kin_list_.assign(K, -1);
  kin_dir_.assign(K, Eigen::Vector2d::Zero());
  kin_of_.assign(M, -1);
  kin_force_.assign(M, Eigen::Vector2d::Zero());
  kin_given_.assign(M, Eigen::Vector2d::Zero());
  slip_members_.assign(M, -1);
  slip_begin_.assign(P + 1, 0);
  slip_row_.assign(3 * M, 0);
  slip_row_begin_.assign(P + 1, 0);
  slip_row_w0_.assign(3 * M, 0.0);
  slip_row_w1_.assign(3 * M, 0.0);
  slip_sum_.assign(2 * (unknowns + 1), 0.0);
}

void ContactSolver::ZeroOutputs() noexcept {
  num_loads_ = 0;
  for (std::int32_t i = 0; i < num_inputs_; ++i) forces_N_[i].setZero();
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    f_N_[j].setZero();
    active_[j] = 0;
  }
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    patch_state_[p].force_N.setZero();
    patch_state_[p].slipping = false;
  }
}

Eigen::Vector3d ContactSolver::total_force_N() const noexcept {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  for (std::int32_t i = 0; i < num_inputs_; ++i) s += forces_N_[i];
  return s;
}

std::int32_t ContactSolver::num_active() const noexcept {
  std::int32_t n = 0;
  for (std::int32_t j = 0; j < num_unique_; ++j) n += active_[j] ? 1 : 0;
  return n;
}

StepStatus ContactSolver::Solve(std::span<const ContactInput> contacts,
                                std::span<const FrictionPatch> patches) noexcept {
  const std::int32_t M = options_.max_contacts;
  const bool overflow = contacts.size() > static_cast<std::size_t>(M);
  num_inputs_ = overflow ? M : static_cast<std::int32_t>(contacts.size());
  num_unique_ = 0;
  num_loads_ = 0;
  iterations_ = 0;
  bool rejected = overflow;
  bool invalid = patches.size() > static_cast<std::size_t>(options_.max_friction_patches);
  num_patches_ = invalid ? 0 : static_cast<std::int32_t>(patches.size());
  if (!ReadPatches(patches)) invalid = true;
  // Stage 1: validate and merge repeated nodes.
  MergeTouches(contacts, invalid, rejected);
  if (!AverageMergedTouches()) invalid = true;
  if (invalid) return GiveUp(StepStatus::kInvalidInput);
  if (num_unique_ == 0) {
    ForgetPrevious();
    table_valid_ = false;
    return rejected ? StepStatus::kSomeRejected : StepStatus::kOk;
  }
  // Stages 2 and 3: gather the contacts' compliance and solve.
  StepStatus status = StepStatus::kOk;
  if (!GatherAndSolve(status)) return GiveUp(StepStatus::kNumericalFailure);
  // Stage 4: per-input outputs.
  WriteOutputs();
  RememberActiveSet();
  if (status != StepStatus::kOk) return status;
  return rejected ? StepStatus::kSomeRejected : StepStatus::kOk;
}

StepStatus ContactSolver::GiveUp(StepStatus status) noexcept {
  ZeroOutputs();
  ForgetPrevious();
  table_valid_ = false;
  return status;
}

bool ContactSolver::ReadPatches(std::span<const FrictionPatch> patches) noexcept {
  // The patches: a unit normal, a finite stick, 0 <= mu; the tangent basis of each.
  bool valid = true;
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    const FrictionPatch& in = patches[static_cast<std::size_t>(p)];
    const double nn = in.n_out.norm();
    const bool ok = in.n_out.allFinite() && nn > 0.5 && nn < 2.0 && in.slide_m.allFinite() &&
                    in.motion_m.allFinite() &&
                    std::isfinite(in.mu_static) && in.mu_static >= 0.0 &&
                    std::isfinite(in.mu_kinetic) && in.mu_kinetic >= 0.0;
    if (!ok) {
      valid = false;
      continue;
    }
    FrictionPatch& q = patch_in_[p];
    q = in;
    q.n_out = in.n_out / nn;
    const Eigen::Vector3d t1 = q.n_out.unitOrthogonal();
    tangent_[p].col(0) = t1;
    tangent_[p].col(1) = q.n_out.cross(t1);
    q.slide_m = tangent_[p] * (tangent_[p].transpose() * in.slide_m);  // its tangential part
    patch_state_[p] = FrictionPatchState{false, q.slide_m, Eigen::Vector3d::Zero()};
  }
  return valid;
}

void ContactSolver::MergeTouches(std::span<const ContactInput> contacts, bool& invalid, bool& rejected) noexcept {
  // m is small: O(m^2) search.
  const Compliance& C = *compliance_;
  for (std::int32_t i = 0; i < num_inputs_; ++i) {
    const ContactInput& c = contacts[i];
    unique_of_input_[i] = -1;
    forces_N_[i].setZero();
    if (!c.u_m.allFinite() || !c.n_out.allFinite()) {
      invalid = true;
      states_[i] = ContactState::kRejectedInvalid;
      continue;
    }
    if (C.IsFixed(c.node)) {
      states_[i] = ContactState::kRejectedFixed;
      rejected = true;
      continue;
    }
    const std::int32_t slot = C.SlotOf(c.node);
    if (slot < 0) {
      states_[i] = ContactState::kRejectedUnknownNode;
      rejected = true;
      continue;
    }
    if (c.patch >= num_patches_ || c.patch < -1) {
      invalid = true;
      states_[i] = ContactState::kRejectedInvalid;
      continue;
    }
    const bool needs_normal = c.mode == ContactMode::kNormalOnly || options_.push_only;
    const double nn = c.n_out.norm();
    if (needs_normal && !(nn > 0.5 && nn < 2.0)) {  // must be (about) unit length
      invalid = true;
      states_[i] = ContactState::kRejectedInvalid;
      continue;
    }
    const std::int32_t j = detail::MergeTouch(slot, c.u_m, slot_.data(), multiplicity_.data(), d_m_.data(),
                                              num_unique_, index_of_slot_.data());
    if (multiplicity_[j] == 1) {
      n_[j].setZero();
      mode_[j] = c.mode;
      patch_of_[j] = c.patch;
    }
    if (nn > 0.0) n_[j] += c.n_out / nn;
    if (c.mode == ContactMode::kFull3d || patch_of_[j] >= 0) mode_[j] = ContactMode::kFull3d;
    unique_of_input_[i] = j;
    states_[i] = ContactState::kActive;
  }
}

bool ContactSolver::AverageMergedTouches() noexcept {
  bool valid = true;
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    index_of_slot_[slot_[j]] = -1;  // merged: the map is clean for the next Solve()
    d_m_[j] /= static_cast<double>(multiplicity_[j]);
    const double nn = n_[j].norm();
    if (nn > 1e-12) {
      n_[j] /= nn;
    } else if (mode_[j] == ContactMode::kNormalOnly || options_.push_only) {
      valid = false;  // merged inputs with opposite normals
    }
    active_[j] = 1;
    slipping_[j] = 0;
    mode_in_[j] = mode_[j];
    kin_of_[j] = -1;
  }
  num_kinetic_ = 0;
  return valid;
}

bool ContactSolver::GatherAndSolve(StepStatus& status) noexcept {
  // Push-only with every contact frictionless (the haptic world's fingertip patches) is the
  // scalar problem of SolveNormalPushOnly. Otherwise C_cc (3u x 3u), and fingertip patches with
  // friction have their own iteration (SolveWithPatches); the rest is SolveGeneral.
  for (std::int32_t j = 0; j < num_unique_; ++j) perm_[j] = j;
  bool all_normal = options_.push_only;
  bool patched = false;
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    all_normal = all_normal && mode_[j] == ContactMode::kNormalOnly;
    patched = patched || patch_of_[j] >= 0;
  }
  // Every fingertip patch of the haptic world: the scalar problem, warm started.
  if (all_normal) return SolveNormalPushOnly(status);
  // Patch nodes are held in 3-D, so patched implies this path.
  table_valid_ = false;
  detail::GatherBlocks(*compliance_, slot_.data(), num_unique_, Ccc_.data(), 3 * options_.max_contacts);
  return patched ? SolveWithPatches(status) : SolveGeneral(status);
}

bool ContactSolver::SolveGeneral(StepStatus& status) noexcept {
  // With push-only, iterate on the set of held contacts:
  //  a) sticking contacts that pull slip (keep their normal constraint only; friction needs
  //     pressure). Sticking -> slipping never reverts, so this happens at most m times;
  //  b) the rest is a linear complementarity problem with a P-matrix (frictionless contacts):
  //     block principal pivoting (Judice and Pires 1994) flips every violating contact at once
  //     while the number of violations keeps falling (3 tries of grace), else one contact by
  //     Murty's least-index rule, which terminates. A pulling contact is released; a released
  //     node the surface pushes into the tip is re-engaged (frictionless).
  BlockPivoting pivoting(num_unique_);
  while (true) {
    if (!SolveActiveSet()) return false;
    if (!options_.push_only) break;
    ComputeContactDisplacements();
    double f_scale = 0.0, d_scale = 0.0;
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      f_scale = std::max(f_scale, f_N_[j].norm());
      d_scale = std::max(d_scale, d_m_[j].norm());
    }
    if (f_scale == 0.0) f_scale = 1.0;
    if (d_scale == 0.0) d_scale = 1.0;
    auto pulls = [&](std::int32_t j) { return f_N_[j].dot(n_[j]) / f_scale > kTol; };
    auto violates = [&](std::int32_t j) {
      return active_[j] ? pulls(j) : (u_c_m_[j] - d_m_[j]).dot(n_[j]) / d_scale > kTol;
    };
    bool slipped = false;
    std::int32_t violations = 0;
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (active_[j] && mode_[j] == ContactMode::kFull3d && pulls(j)) slipped = true;
      violations += violates(j) ? 1 : 0;
    }
    if (!slipped && violations == 0) break;
    if (iterations_ >= options_.max_active_set_iterations) {
      status = StepStatus::kNotConverged;
      break;
    }
    ++iterations_;
    if (slipped) {
      for (std::int32_t j = 0; j < num_unique_; ++j) {
        if (active_[j] && mode_[j] == ContactMode::kFull3d && pulls(j)) {
          mode_[j] = ContactMode::kNormalOnly;
          slipping_[j] = 1;
        }
      }
      continue;
    }
    const bool block = pivoting.Block(violations);
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (!violates(j)) continue;
      if (active_[j]) {
        active_[j] = 0;
      } else {
        active_[j] = 1;
        if (mode_[j] == ContactMode::kFull3d) {  // re-engages frictionless
          mode_[j] = ContactMode::kNormalOnly;
          slipping_[j] = 1;
        }
      }
      if (!block) break;  // least index
    }
  }
  return true;
}

void ContactSolver::WriteOutputs() noexcept {
  // Per input, a merged node's force split evenly; a load per held node.
  for (std::int32_t i = 0; i < num_inputs_; ++i) {
    const std::int32_t j = unique_of_input_[i];
    if (j < 0) continue;
    if (active_[j]) {
      forces_N_[i] = f_N_[j] / static_cast<double>(multiplicity_[j]);
      const bool slips = slipping_[j] || (patch_of_[j] >= 0 && patch_state_[patch_of_[j]].slipping);
      states_[i] = slips ? ContactState::kSlipping : ContactState::kActive;
    } else {
      forces_N_[i].setZero();
      states_[i] = ContactState::kReleased;
    }
  }
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    if (active_[j]) loads_[num_loads_++] = NodeLoad{slot_[j], f_N_[j]};
  }
}

void ContactSolver::GatherNormalCompliance() noexcept {
  // Which nodes the previous Solve() touched too (also the warm start's map).
  for (std::int32_t j = 0; j < num_unique_; ++j) prev_index_[j] = prev_of_slot_[slot_[j]];
  AssignTablePositions();
  PrefetchNewBlocks();
  FillNormalCompliance();
}

void ContactSolver::AssignTablePositions() noexcept {
  const std::int32_t u = num_unique_;
  const std::int32_t M = options_.max_contacts;
  // The blocks of a large compliance lie far apart in memory (a cache miss or more each), so
  // reading them is the costliest part of the force path; fingertips move a fraction of a node
  // spacing per haptic step. So the blocks stay in a table between steps: a node keeps its
  // table position while it is touched in consecutive steps, and only the pairs with a node
  // new this step are read from the compliance. A node not touched this step gives its position
  // up, so two nodes that are both old have been touched together since the later one came,
  // and their block is in the table.
  if (!table_valid_) {
    for (std::int32_t p = 0; p < M; ++p) free_pos_[p] = M - 1 - p;
    num_free_ = M;
    for (std::int32_t k = 0; k < num_prev_; ++k) prev_pos_[k] = -1;
    table_valid_ = true;
  }
  for (std::int32_t k = 0; k < num_prev_; ++k) prev_kept_[k] = 0;
  for (std::int32_t j = 0; j < u; ++j) {
    const std::int32_t k = prev_index_[j];
    if (k >= 0 && prev_pos_[k] >= 0) {
      pos_[j] = prev_pos_[k];
      prev_kept_[k] = 1;
      is_new_[j] = 0;
    } else {
      pos_[j] = -1;
      is_new_[j] = 1;
    }
  }
  for (std::int32_t k = 0; k < num_prev_; ++k) {
    if (prev_pos_[k] >= 0 && !prev_kept_[k]) free_pos_[num_free_++] = prev_pos_[k];
  }
  for (std::int32_t j = 0; j < u; ++j) {
    if (is_new_[j]) pos_[j] = free_pos_[--num_free_];  // u <= M positions: never runs out
  }
}

void ContactSolver::PrefetchNewBlocks() const noexcept {
  const std::int32_t u = num_unique_;
  const Compliance& C = *compliance_;
  // The new pairs' blocks are cache (and TLB) misses in a large compliance: ask for all of them
  // before reading any, so that the misses overlap instead of coming one after the other (a
  // patch that gains a row of nodes needs a few hundred). A hint only: same values read.
  const float* c32 = C.data_f32();
  const double* c64 = C.data_f64();
  if (c32 == nullptr && c64 == nullptr) return;
  for (std::int32_t j = 0; j < u; ++j) {
    if (!is_new_[j]) continue;
    for (std::int32_t i = 0; i < u; ++i) {
      if (is_new_[i] && i > j) continue;  // both new: once
      const std::int32_t lo = std::min(slot_[i], slot_[j]), hi = std::max(slot_[i], slot_[j]);
      const std::int64_t off = 9 * Compliance::PackedIndex(lo, hi);
      if (c32 != nullptr) {
        __builtin_prefetch(c32 + off);
        __builtin_prefetch(c32 + off + 8);
      } else {
        __builtin_prefetch(c64 + off);
        __builtin_prefetch(c64 + off + 8);
      }
    }
  }
}

void ContactSolver::FillNormalCompliance() noexcept {
  const std::int32_t u = num_unique_;
  const std::int32_t M = options_.max_contacts;
  const Compliance& C = *compliance_;
  // S_ij = n_i^T C_ij n_j; the table keeps C_ab for table positions a <= b (packed), and S_ab
  // as last computed with the normals in pos_n_.
  for (std::int32_t j = 0; j < u; ++j) {
    same_n_[j] = !is_new_[j] && std::memcmp(pos_n_[pos_[j]].data(), n_[j].data(), sizeof(double) * 3) == 0;
  }
  // S_ holds each pair at its table positions; a pair of old nodes with the normals bit for bit
  // those of its last computation keeps its entry (both nodes kept their positions since), so
  // only the pairs of a new or turned node are computed: each once.
  for (std::int32_t j = 0; j < u; ++j) {
    if (same_n_[j]) continue;
    for (std::int32_t i = 0; i < u; ++i) {
      if (!same_n_[i] && i > j) continue;  // both computed here: once, at the later of the two
      const bool ij = pos_[i] <= pos_[j];
      const std::int32_t a = ij ? i : j, b = ij ? j : i;  // pos_[a] <= pos_[b]
      const std::int64_t pb = pos_[b];
      const std::int64_t packed = pb * (pb + 1) / 2 + pos_[a];
      double* blk = table_.data() + 9 * packed;
      Eigen::Map<Eigen::Matrix3d> B(blk);
      if (is_new_[i] || is_new_[j]) B = C.Block(slot_[a], slot_[b]);
      const double v = n_[a].dot(B * n_[b]);
      S_[static_cast<std::size_t>(pos_[j]) * M + pos_[i]] = v;
      S_[static_cast<std::size_t>(pos_[i]) * M + pos_[j]] = v;
    }
  }
  for (std::int32_t j = 0; j < u; ++j) pos_n_[pos_[j]] = n_[j];
}

void ContactSolver::WarmStartActiveSet() noexcept {
  // Nodes touched in the previous Solve() start as they ended there (the fingertips move little
  // in one haptic step, so the held set is mostly right and one factorization usually settles
  // it); new nodes start held. The LCP has a unique solution (S is positive definite), so the
  // start changes only the work, not the answer.
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    const std::int32_t k = prev_index_[j];
    active_[j] = k >= 0 ? prev_active_[k] : 1;
  }
}

void ContactSolver::RememberActiveSet() noexcept {
  ForgetPrevious();
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    prev_slot_[j] = slot_[j];
    prev_active_[j] = active_[j];
    prev_pos_[j] = table_valid_ ? pos_[j] : -1;
    prev_of_slot_[slot_[j]] = j;
  }
  num_prev_ = num_unique_;
}

void ContactSolver::ForgetPrevious() noexcept {
  for (std::int32_t k = 0; k < num_prev_; ++k) prev_of_slot_[prev_slot_[k]] = -1;
  num_prev_ = 0;
}

bool ContactSolver::SolveNormalPushOnly(StepStatus& status) noexcept {
  const std::int32_t u = num_unique_;
  // S = N^T C_cc N (u x u): every contact holds only its normal, so the 3u x 3u problem is a
  // u x u one (9x less to factor, 3x less per displacement check).
  GatherNormalCompliance();
  double d_scale = 0.0;
  for (std::int32_t j = 0; j < u; ++j) {
    dn_m_[j] = n_[j].dot(d_m_[j]);
    d_scale = std::max(d_scale, d_m_[j].norm());
  }
  if (d_scale == 0.0) d_scale = 1.0;
  WarmStartActiveSet();
  // The same pivoting as the general path (block principal pivoting with Murty's rule as the
  // fallback), on the normal forces lambda (f = lambda n: push is lambda < 0).
  BlockPivoting pivoting(u);
  while (true) {
    const std::int32_t r = ListActiveNormals();
    if (r > 0 && !SolveActiveNormals(r)) return false;
    const std::int32_t violations = FindNormalViolations(r, d_scale);
    if (violations == 0) break;
    if (iterations_ >= options_.max_active_set_iterations) {
      status = StepStatus::kNotConverged;
      break;
    }
    ++iterations_;
    const bool block = pivoting.Block(violations);
    for (std::int32_t j = 0; j < u; ++j) {
      if (!violates_[j]) continue;
      active_[j] = active_[j] ? 0 : 1;
      if (!block) break;  // least index
    }
  }
  for (std::int32_t j = 0; j < u; ++j) {
    slipping_[j] = 0;  // frictionless from the start: held, not slipping
    f_N_[j] = active_[j] ? Eigen::Vector3d(lambda_N_[j] * n_[j]) : Eigen::Vector3d::Zero();
  }
  return true;
}

std::int32_t ContactSolver::ListActiveNormals() noexcept {
  std::int32_t r = 0;
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    lambda_N_[j] = 0.0;
    if (active_[j]) {
      act_pos_[r] = pos_[j];
      act_[r++] = j;
    }
  }
  return r;
}

bool ContactSolver::SolveActiveNormals(std::int32_t r) noexcept {
  const std::int32_t M = options_.max_contacts;
  for (std::int32_t b = 0; b < r; ++b) {
    const double* Sb = S_.data() + static_cast<std::size_t>(act_pos_[b]) * M;
    double* Lb = L_.data() + static_cast<std::size_t>(b) * r;
    for (std::int32_t a = b; a < r; ++a) Lb[a] = Sb[act_pos_[a]];
    Lb[b] += eps_m_per_N_;
    rhs_[b] = dn_m_[act_[b]];
  }
  if (r <= detail::kSmallSpdMax) {  // a few nodes: the register kernel (eps is in L_ already)
    if (!detail::SmallSpdSolve(L_.data(), r, r, 0.0, rhs_.data(), detail::BestIsa())) return false;
  } else {
    const detail::Isa isa = detail::BestIsa();
    if (!detail::FactorSpd(L_.data(), r, r, isa)) return false;
    detail::SolveFactoredSpd(L_.data(), r, r, rhs_.data(), 1, r, isa);
  }
  for (std::int32_t b = 0; b < r; ++b) {
    if (!std::isfinite(rhs_[b])) return false;
    lambda_N_[act_[b]] = rhs_[b];
  }
  return true;
}

std::int32_t ContactSolver::FindNormalViolations(std::int32_t r, double d_scale) noexcept {
  const std::int32_t M = options_.max_contacts;
  double f_scale = 0.0;
  for (std::int32_t b = 0; b < r; ++b) f_scale = std::max(f_scale, std::abs(rhs_[b]));
  if (f_scale == 0.0) f_scale = 1.0;
  // A held node violates if it pulls; a released one if the surface would push into the tip.
  std::int32_t violations = 0;
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    bool v;
    if (active_[j]) {
      v = lambda_N_[j] / f_scale > kTol;
    } else {
      const double* Sj = S_.data() + static_cast<std::size_t>(pos_[j]) * M;
      double un = 0.0;
      for (std::int32_t b = 0; b < r; ++b) un += Sj[act_pos_[b]] * rhs_[b];
      v = (un - dn_m_[j]) / d_scale > kTol;
    }
    violates_[j] = v ? 1 : 0;
    violations += v ? 1 : 0;
  }
  return violations;
}

int ContactSolver::AssembleHeld(bool fill_matrix, int from_row) noexcept {
  // Rows of G: 3 per sticking contact, 1 per frictionless one (n^T), node by node in perm_'s
  // order (C_cc is gathered whole, so any order reads it).
  const int ld = 3 * options_.max_contacts;
  int r = 0;
  for (std::int32_t q = 0; q < num_unique_; ++q) {
    const std::int32_t j = perm_[q];
    if (!active_[j]) {
      row_of_[j] = -1;
      f_N_[j].setZero();
      continue;
    }
    row_of_[j] = r;
    r += mode_[j] == ContactMode::kFull3d ? 3 : 1;
  }
  // The nodes whose rows are refilled: from the first at or after from_row in the order (rows
  // grow along it).
  std::int32_t q_from = 0;
  while (q_from < num_unique_ && !(active_[perm_[q_from]] && row_of_[perm_[q_from]] >= from_row)) ++q_from;
  for (std::int32_t q = 0; q < num_unique_; ++q) {
    const std::int32_t j = perm_[q];
    if (!active_[j]) continue;
    const bool fj = mode_[j] == ContactMode::kFull3d;
    // The lower triangle only (blocks of the nodes at or after j in the order, whole diagonal
    // blocks): every factor and solve here reads rows >= column.
    for (std::int32_t qi = std::max(q, q_from); qi < num_unique_ && fill_matrix; ++qi) {
      const std::int32_t i = perm_[qi];
      if (!active_[i]) continue;
      const bool fi = mode_[i] == ContactMode::kFull3d;
      Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<>> Cij(
          Ccc_.data() + static_cast<std::ptrdiff_t>(3 * j) * ld + 3 * i, 3, 3, Eigen::OuterStride<>(ld));
      double* a = A_.data() + static_cast<std::ptrdiff_t>(row_of_[j]) * ld + row_of_[i];
      if (fi && fj) {
        for (int c = 0; c < 3; ++c)
          for (int rr = 0; rr < 3; ++rr) a[c * ld + rr] = Cij(rr, c);
      } else if (fi) {  // column n_j
        const Eigen::Vector3d v = Cij * n_[j];
        for (int rr = 0; rr < 3; ++rr) a[rr] = v[rr];
      } else if (fj) {  // row n_i^T
        const Eigen::RowVector3d v = n_[i].transpose() * Cij;
        for (int c = 0; c < 3; ++c) a[c * ld] = v[c];
      } else {
        a[0] = n_[i].dot(Cij * n_[j]);
      }
    }
    if (fj) {
      for (int c = 0; c < 3; ++c) rhs_[row_of_[j] + c] = d_m_[j][c];
    } else {
      rhs_[row_of_[j]] = n_[j].dot(d_m_[j]);
    }
  }
  return r;
}

bool ContactSolver::ForcesFromRows() noexcept {
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    if (!active_[j]) continue;
    const int k = row_of_[j];
    if (mode_[j] == ContactMode::kFull3d) {
      f_N_[j] = Eigen::Vector3d(rhs_[k], rhs_[k + 1], rhs_[k + 2]);
    } else if (kin_of_[j] >= 0) {  // with its kinetic friction
      f_N_[j] = rhs_[k] * n_[j] + tangent_[patch_of_[j]] * kin_force_[j];
    } else {
      f_N_[j] = rhs_[k] * n_[j];
    }
    if (!f_N_[j].allFinite()) return false;
  }
  return true;
}

bool ContactSolver::SolveActiveSet() noexcept {
  const int ld = 3 * options_.max_contacts;
  std::int32_t held = 0, held_3d = 0;
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    held += active_[j] ? 1 : 0;
    held_3d += active_[j] && mode_[j] == ContactMode::kFull3d ? 1 : 0;
  }
  const int rows = 3 * held_3d + (held - held_3d);
  if (rows == 0) {
    for (std::int32_t j = 0; j < num_unique_; ++j) f_N_[j].setZero();
    return true;
  }
  // A = G C_cc G^T, its lower triangle (all the Cholesky reads). With
  // every contact held and sticking (r = 3 u) that is C_cc as gathered, which the small solver
  // reads in place.
  fac_valid_ = false;  // A_ gets another matrix
  const bool small = rows <= detail::kSmallSpdMax;
  const bool in_place = small && rows == 3 * num_unique_;
  const int r = AssembleHeld(!in_place);
  if (small) {
    const double* A = in_place ? Ccc_.data() : A_.data();
    if (!detail::SmallSpdSolve(A, r, ld, eps_m_per_N_, rhs_.data(), detail::BestIsa())) return false;
  } else {
    if (eps_m_per_N_ > 0.0) {
      for (int k = 0; k < r; ++k) A_[static_cast<std::ptrdiff_t>(k) * ld + k] += eps_m_per_N_;
    }
    if (!FactorSpd(A_.data(), r, ld)) return false;
    SolveFactored(A_.data(), r, ld, rhs_.data(), 1, ld);
  }
  return ForcesFromRows();
}

bool ContactSolver::SolvePatchedSystem(bool refactor, bool same_columns) noexcept {
  // Held rows as in SolveActiveSet; a sticking patch's nodes are held at d* + its slide. A
  // slipping patch's slide s (2 tangent coordinates) is unknown: with A y = b0 + B s
  // (B puts the tangent basis T into the rows of the patch's held nodes), y = z0 + Z s with
  // z0 = A^-1 b0 and Z = A^-1 B, and its two cone equations
  //   Phi y = sum_j (T^T + mu_k e n^T) f_j = F_t - mu_k F_n e = 0   (F_n = -n . sum f_j)
  // give the 2P x 2P system (Phi Z) s = -Phi z0. The columns of Z share A's factor.
  // same_columns: only the slipping patches' directions changed since the last call (the held
  // set, the modes, the slipping patches and the sticking slides did not): z0 and Z stand, and
  // only the cone equations are formed and solved again (bit for bit what a whole call gives).
  const bool new_columns = !same_columns;
  const int p0 = refactor && new_columns ? ResumableRows() : 0;
  const int r = same_columns ? patched_rows_ : AssembleHeld(refactor, p0);
  patched_rows_ = r;
  num_slipping_ = 0;
  for (std::int32_t k = 0; k < num_kinetic_; ++k) kin_of_[kin_list_[k]] = -1;
  num_kinetic_ = 0;
  if (new_columns) AddSticks();
  if (r == 0) {
    fac_valid_ = false;
    return true;
  }
  if (refactor && new_columns && !FactorHeld(r, p0)) return false;
  ListSlippingPatches();
  ListKineticNodes();
  SolveColumns(r, same_columns);
  if (num_slipping_ + num_kinetic_ > 0 && !SolveSlides(r)) return false;
  return ForcesFromRows();
}

void ContactSolver::AddSticks() noexcept {
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    const std::int32_t p = patch_of_[j];
    if (!active_[j] || p < 0 || mode_[j] != ContactMode::kFull3d || patch_state_[p].slipping) continue;
    for (int c = 0; c < 3; ++c) rhs_[row_of_[j] + c] += patch_in_[p].slide_m[c];
  }
}

bool ContactSolver::FactorHeld(int r, int p0) noexcept {
  const int ld = 3 * options_.max_contacts;
  if (eps_m_per_N_ > 0.0) {
    for (int k = p0; k < r; ++k) A_[static_cast<std::ptrdiff_t>(k) * ld + k] += eps_m_per_N_;
  }
  fac_valid_ = false;
  const bool ok = p0 > 0 ? detail::ResumeFactorSpd(A_.data(), r, ld, p0, detail::BestIsa()) : FactorSpd(A_.data(), r, ld);
  if (!ok) return false;
  RememberFactored();
  return true;
}

void ContactSolver::ListSlippingPatches() noexcept {
  // The slipping patches that hold a node in 3-D (a patch whose nodes all went frictionless
  // has no tangential force and no slide to find), each with its active nodes (members from
  // slip_begin_[a] to slip_begin_[a + 1]) and its cone equations as weights on the held rows
  // (from slip_row_begin_[a]): w_k = t_k + mu e_k n on a 3-D node's three rows, w_k . n_j on a
  // frictionless node's one row (f = lambda n). One scan of the contacts per slipping patch,
  // for the slide's columns and the equations below.
  std::int32_t ns = 0, q = 0, t = 0;
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    if (!patch_state_[p].slipping) continue;
    const double mu = given_force_ ? 0.0 : patch_in_[p].mu_kinetic;
    const Eigen::Vector3d w0 = tangent_[p].col(0) + mu * slip_dir_[p][0] * patch_in_[p].n_out;
    const Eigen::Vector3d w1 = tangent_[p].col(1) + mu * slip_dir_[p][1] * patch_in_[p].n_out;
    const std::int32_t begin = q, row_begin = t;
    bool holds = false;
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (!active_[j] || patch_of_[j] != p) continue;
      slip_members_[q++] = j;
      if (mode_[j] == ContactMode::kFull3d) {
        holds = true;
        for (int c = 0; c < 3; ++c) {
          slip_row_[t] = row_of_[j] + c;
          slip_row_w0_[t] = w0[c];
          slip_row_w1_[t++] = w1[c];
        }
      } else {
        slip_row_[t] = row_of_[j];
        slip_row_w0_[t] = w0.dot(n_[j]);
        slip_row_w1_[t++] = w1.dot(n_[j]);
      }
    }
    if (!holds) {
      q = begin;
      t = row_begin;
      continue;
    }
    slip_begin_[ns] = begin;
    slip_row_begin_[ns] = row_begin;
    slipping_list_[ns++] = p;
  }
  slip_begin_[ns] = q;
  slip_row_begin_[ns] = t;
  num_slipping_ = ns;
}

void ContactSolver::SolveColumns(int r, bool same_columns) noexcept {
  // Z = A^-1 B: B puts the tangent basis into the rows of each slipping patch's held nodes.
  // z0 and Z are solved together, b0 in the column before Z's (Z_'s column 0): one pass of the
  // lane solve takes eight columns, so the right-hand side rides along with up to three
  // slipping patches instead of a pass of its own.
  if (same_columns) {
    std::copy(Z_.begin(), Z_.begin() + r, rhs_.begin());  // z0, kept in Z_'s column 0
    return;
  }
  const int ld = 3 * options_.max_contacts;
  for (std::int32_t a = 0; a < num_slipping_; ++a) {
    const std::int32_t p = slipping_list_[a];
    for (int c = 0; c < 2; ++c) {
      double* z = Zcol(2 * a + c);
      std::fill(z, z + r, 0.0);
      for (std::int32_t m = slip_begin_[a]; m < slip_begin_[a + 1]; ++m) {
        const std::int32_t j = slip_members_[m];
        if (mode_[j] != ContactMode::kFull3d) continue;
        for (int k = 0; k < 3; ++k) z[row_of_[j] + k] = tangent_[p](k, c);
      }
    }
  }
  KineticColumns(r);
  std::copy(rhs_.begin(), rhs_.begin() + r, Z_.begin());
  SolveFactored(A_.data(), r, ld, Z_.data(), 1 + 2 * (num_slipping_ + num_kinetic_), ld);
  std::copy(Z_.begin(), Z_.begin() + r, rhs_.begin());
}

Eigen::Vector2d ContactSolver::KineticDirection(std::int32_t p) const noexcept {
  // Kinetic friction opposes the sliding. A slipping patch's nodes slide the way the patch
  // does (its cone's direction: a node held normal-only then lies on the same cone as the
  // patch). Under a moving fingertip the nodes of a sticking patch that cannot be held along
  // the surface (they pull) slide the way the fingertip moves over them. A sticking patch
  // under a fingertip at rest: none, as before (0.1 um a step for every patch let a fingertip
  // held on the beating horn toggle with the beat: 372 buzzing steps against 249).
  if (patch_in_[p].mu_kinetic <= 0.0) return Eigen::Vector2d::Zero();
  if (patch_state_[p].slipping) return slip_dir_[p];
  const Eigen::Vector2d m = MotionAlongSurface(p);
  const bool slides = m.norm() > kRestMotion_m || (patch_in_[p].slipped_before && m.norm() > kKineticRestMotion_m);
  return slides ? Eigen::Vector2d(m.normalized()) : Eigen::Vector2d::Zero();
}

void ContactSolver::ListKineticNodes() noexcept {
  // The nodes held along their normal only (they pulled when held in 3-D) of a patch that holds
  // no node in 3-D, whose patch gives them a way to slide: each carries the kinetic friction
  // mu_k N_j along it, N_j its own normal force, as a tangential load g_j = -mu_k y_j e (y_j its
  // row: the normal force, negative for a push). The load enters the solve as two more unknowns
  // with their columns, and two equations tie it to the node's normal force: the exact static
  // FEM answer for that load, as a slip's is. Without it such a patch carried no tangential
  // force at all, and on the horn toggled between none and its whole cone (docs/fem.md). Only
  // such patches: where some node still holds the patch in 3-D, the patch's own stick or slip
  // carries its friction, and kinetic loads on its other nodes made a peer's solve of a contact
  // set differ from its sender's in 84 of 39,590 steps (5 without; a peer's patch does not know
  // the way its sender's fingertip moved).
  for (std::int32_t q = 0; q < num_unique_ && num_kinetic_ < max_kinetic_; ++q) {
    const std::int32_t j = perm_[q];
    const std::int32_t p = patch_of_[j];
    if (!active_[j] || p < 0 || mode_[j] != ContactMode::kNormalOnly) continue;
    bool holds = false;  // a node of its patch held in 3-D (m is small: a scan)
    for (std::int32_t i = 0; i < num_unique_ && !holds; ++i) {
      holds = active_[i] && patch_of_[i] == p && mode_[i] == ContactMode::kFull3d;
    }
    if (holds) continue;
    const Eigen::Vector2d e = KineticDirection(p);
    if (e.squaredNorm() == 0.0) continue;
    kin_of_[j] = num_kinetic_;
    kin_dir_[num_kinetic_] = e;
    kin_list_[num_kinetic_++] = j;
  }
}

void ContactSolver::KineticColumns(int r) noexcept {
  // A tangential load t at node j moves the held rows by G C_{.j} t, so A y = b0 - sum_j G C_{.j}
  // T g_j: the columns -G C_{.j} T (two per kinetic node), after the slides' in Z_.
  const int ld = 3 * options_.max_contacts;
  for (std::int32_t k = 0; k < num_kinetic_; ++k) {
    const std::int32_t j = kin_list_[k];
    const Eigen::Matrix<double, 3, 2>& T = tangent_[patch_of_[j]];
    for (int c = 0; c < 2; ++c) {
      double* z = Zcol(2 * (num_slipping_ + k) + c);
      std::fill(z, z + r, 0.0);
      for (std::int32_t i = 0; i < num_unique_; ++i) {
        if (!active_[i]) continue;
        Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<>> Cij(
            Ccc_.data() + static_cast<std::ptrdiff_t>(3 * j) * ld + 3 * i, 3, 3, Eigen::OuterStride<>(ld));
        const Eigen::Vector3d v = Cij * T.col(c);
        if (mode_[i] == ContactMode::kFull3d) {
          for (int rr = 0; rr < 3; ++rr) z[row_of_[i] + rr] = -v[rr];
        } else {
          z[row_of_[i]] = -n_[i].dot(v);
        }
      }
    }
  }
}

void ContactSolver::MarkKineticPatchesSlipping() noexcept {
  // A patch that holds no node in 3-D but kinetic ones slides: it slips, and its slide is where
  // the material under it went along the surface (the mean tangential displacement of those
  // nodes), so that its anchor, the contact point minus the slide, is the material point under
  // the fingertip. Kept at the stick instead, the anchor stayed behind a stroke, the patch
  // drifted off the fingertip and its nodes came and went (a second difference of up to 1.1 F_n
  // on the horn).
  const int ld = 3 * options_.max_contacts;
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    bool holds = false;
    std::int32_t kinetic = 0;
    Eigen::Vector3d u_sum = Eigen::Vector3d::Zero();
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (!active_[j] || patch_of_[j] != p) continue;
      holds = holds || mode_[j] == ContactMode::kFull3d;
      if (kin_of_[j] < 0) continue;
      ++kinetic;
      for (std::int32_t i = 0; i < num_unique_; ++i) {
        if (!active_[i]) continue;
        Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<>> Cji(
            Ccc_.data() + static_cast<std::ptrdiff_t>(3 * i) * ld + 3 * j, 3, 3, Eigen::OuterStride<>(ld));
        u_sum.noalias() += Cji * f_N_[i];
      }
    }
    if (holds || kinetic == 0) continue;
    if (!patch_state_[p].slipping) slip_dir_[p] = KineticDirection(p);
    patch_state_[p].slipping = true;
    patch_state_[p].slide_m = tangent_[p] * (tangent_[p].transpose() * u_sum) / static_cast<double>(kinetic);
  }
}

bool ContactSolver::SolveSlides(int r) noexcept {
  const std::int32_t ns = num_slipping_;
  const int n2 = 2 * ns;
  const int n = n2 + 2 * num_kinetic_;  // unknowns: the slides, then the kinetic loads
  // Phi_a applied to the columns (the patch's held nodes' rows), both equations of a patch
  // from one read of each row. With given forces the equations are T^T F = g instead
  // (symmetric: Phi Z = B^T A^-1 B). A kinetic node's load g_j adds T^T T g_j = g_j to its
  // patch's equations (the weights' n part is orthogonal to T).
  // Every column's sums at once (column 0: z0, as rhs_; then Z).
  const std::ptrdiff_t ldz = 3 * static_cast<std::ptrdiff_t>(options_.max_contacts);
  double* s0 = slip_sum_.data();
  double* s1 = s0 + (n + 1);
  for (std::int32_t a = 0; a < ns; ++a) {
    const std::int32_t b = slip_row_begin_[a];
    detail::WeightedRowSums(Z_.data(), ldz, n + 1, slip_row_.data() + b, slip_row_w0_.data() + b,
                            slip_row_w1_.data() + b, slip_row_begin_[a + 1] - b, s0, s1, detail::BestIsa());
    const Eigen::Vector2d g = given_force_ ? slip_force_[slipping_list_[a]] : Eigen::Vector2d::Zero();
    slip_rhs_[2 * a] = g[0] - s0[0];
    slip_rhs_[2 * a + 1] = g[1] - s1[0];
    for (int col = 1; col <= n; ++col) {
      slip_M_[static_cast<std::ptrdiff_t>(col - 1) * n + 2 * a] = s0[col];
      slip_M_[static_cast<std::ptrdiff_t>(col - 1) * n + 2 * a + 1] = s1[col];
    }
    for (std::int32_t m = slip_begin_[a]; m < slip_begin_[a + 1]; ++m) {
      const std::int32_t k = kin_of_[slip_members_[m]];
      if (k < 0) continue;
      slip_M_[static_cast<std::ptrdiff_t>(n2 + 2 * k) * n + 2 * a] += 1.0;
      slip_M_[static_cast<std::ptrdiff_t>(n2 + 2 * k + 1) * n + 2 * a + 1] += 1.0;
    }
  }
  // A kinetic node's two equations: g_j + mu_k e y_j = 0 (kinetic friction mu_k N_j along e,
  // N_j = -y_j), or g_j = its given load.
  for (std::int32_t k = 0; k < num_kinetic_; ++k) {
    const std::int32_t j = kin_list_[k];
    const int row = row_of_[j];
    const double mu = patch_in_[patch_of_[j]].mu_kinetic;
    for (int c = 0; c < 2; ++c) {
      const int eq = n2 + 2 * k + c;
      const double w = mu * kin_dir_[k][c];
      for (int col = 1; col <= n; ++col) slip_M_[static_cast<std::ptrdiff_t>(col - 1) * n + eq] = w * Z_[(col)*ldz + row];
      slip_M_[static_cast<std::ptrdiff_t>(eq) * n + eq] += 1.0;
      slip_rhs_[eq] = -w * Z_[row];
    }
  }
  if (!detail::LuInPlace(slip_M_.data(), n, n, slip_piv_.data())) return false;
  detail::LuSolveInPlace(slip_M_.data(), n, n, slip_piv_.data(), slip_rhs_.data());
  for (int col = 0; col < n; ++col) {
    if (!std::isfinite(slip_rhs_[col])) return false;
  }
  // y = z0 + Z s, a matrix-vector product over Z's columns.
  Eigen::Map<Eigen::VectorXd>(rhs_.data(), r).noalias() +=
      Eigen::Map<const Eigen::MatrixXd, 0, Eigen::OuterStride<>>(Zcol(0), r, n, Eigen::OuterStride<>(ldz)) *
      Eigen::Map<const Eigen::VectorXd>(slip_rhs_.data(), n);
  for (std::int32_t a = 0; a < ns; ++a) {
    const std::int32_t p = slipping_list_[a];
    patch_state_[p].slide_m = tangent_[p] * Eigen::Vector2d(slip_rhs_[2 * a], slip_rhs_[2 * a + 1]);
  }
  for (std::int32_t k = 0; k < num_kinetic_; ++k) {
    kin_force_[kin_list_[k]] = Eigen::Vector2d(slip_rhs_[n2 + 2 * k], slip_rhs_[n2 + 2 * k + 1]);
  }
  return true;
}

int ContactSolver::ResumableRows() const noexcept {
  if (!fac_valid_ || detail::BestIsa() != detail::Isa::kAvx512) return 0;
  int rows = 0;
  std::int32_t k = 0;  // held nodes matched so far
  for (std::int32_t q = 0; q < num_unique_ && k < fac_count_; ++q) {
    const std::int32_t j = perm_[q];
    if (!active_[j]) continue;
    const bool full3d = mode_[j] == ContactMode::kFull3d;
    if (fac_slot_[k] != slot_[j] || (fac_full3d_[k] != 0) != full3d) break;
    if (!full3d && std::memcmp(fac_n_[k].data(), n_[j].data(), sizeof(double) * 3) != 0) break;
    rows += full3d ? 3 : 1;
    ++k;
  }
  return rows;
}

void ContactSolver::MoveViolatorsLast() noexcept {
  // A node that violates now is the one likely to change again in this call (a sticking node
  // that pulls turns frictionless, then is mostly released the round after): last in the order,
  // its next change leaves every row before it factored.
  std::int32_t k = 0;
  for (std::int32_t q = 0; q < num_unique_; ++q) {
    if (violates_[perm_[q]]) perm_scratch_[k++] = perm_[q];
  }
  if (k == 0) return;
  std::int32_t w = 0;
  for (std::int32_t q = 0; q < num_unique_; ++q) {
    if (!violates_[perm_[q]]) perm_[w++] = perm_[q];
  }
  std::copy(perm_scratch_.begin(), perm_scratch_.begin() + k, perm_.begin() + w);
}

void ContactSolver::RememberFactored() noexcept {
  fac_count_ = 0;
  for (std::int32_t q = 0; q < num_unique_; ++q) {
    const std::int32_t j = perm_[q];
    if (!active_[j]) continue;
    fac_slot_[fac_count_] = slot_[j];
    fac_n_[fac_count_] = n_[j];
    fac_full3d_[fac_count_++] = mode_[j] == ContactMode::kFull3d ? 1 : 0;
  }
  fac_valid_ = true;
}

Eigen::Vector2d ContactSolver::SlidOver(std::int32_t a) const noexcept {
  const std::int32_t p = slipping_list_[a];
  return tangent_[p].transpose() * patch_in_[p].slide_m - Eigen::Vector2d(slip_rhs_[2 * a], slip_rhs_[2 * a + 1]);
}

bool ContactSolver::WouldStick(std::int32_t a) const noexcept {
  // Held at its stick instead of its slide s_a, the patch's rows would be y + Z_a (T^T stick -
  // s_a) with everything else as solved (the system is linear in the slides).
  const std::int32_t p = slipping_list_[a];
  const FrictionPatch& in = patch_in_[p];
  const Eigen::Vector2d delta = SlidOver(a);
  const double* z0 = Zcol(2 * a);
  const double* z1 = Zcol(2 * a + 1);
  // Its kinetic nodes lie on its cone whatever it does: the rest decides.
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    if (!active_[j] || patch_of_[j] != p || kin_of_[j] >= 0) continue;
    const int k = row_of_[j];
    auto row = [&](int c) { return rhs_[k + c] + z0[k + c] * delta[0] + z1[k + c] * delta[1]; };
    force += mode_[j] == ContactMode::kFull3d ? Eigen::Vector3d(row(0), row(1), row(2))
                                              : Eigen::Vector3d(row(0) * n_[j]);
  }
  const double f_n = -in.n_out.dot(force);
  const Eigen::Vector2d f_t = tangent_[p].transpose() * force;
  return f_t.norm() <= in.mu_kinetic * std::max(f_n, 0.0);
}

int ContactSolver::TurnTowardTheSlide(std::int32_t a, double tol) noexcept {
  // Kinetic friction opposes the sliding: a slipping patch's force on the body runs along the
  // way the fingertip slid over the material, w = stick - s = lambda e (lambda >= 0). With the
  // held set fixed, the patch's force is affine in its slide (the columns Z of its slide):
  // F_t(s) = F_sigma + G (s - sigma), F_n(s) = N_sigma + h . (s - sigma), sigma the stick and
  // G its tangential stiffness (SPD). The cone F_t = mu F_n e then reads
  //   (lambda G + mu N I) e = F_sigma,  N = N_sigma - lambda h . e,
  // and for a given N, |(lambda G + mu N I)^-1 F_sigma| falls from |F_sigma| / (mu N) > 1 (the
  // stick is outside the cone) to 0 as lambda grows: one root, found by safeguarded Newton,
  // and N follows in a few passes. The other patches' slides are held as they are; the rounds
  // of SolveWithPatches take them along. Taking the slide's direction as the next one (a fixed
  // point) diverges where the slip is small against what a turn of the force moves the slide:
  // a fingertip that just left its cone got an arbitrary direction when the rounds ran out, and
  // a stroke that started from a press jumped by up to 1.1 N (docs/fem.md).
  // Returns 1 if the direction turned by more than tol, 0 if it agrees, -1 if the stick is
  // inside the cone (no slip).
  const std::int32_t p = slipping_list_[a];
  const FrictionPatch& in = patch_in_[p];
  const double* z0 = Zcol(2 * a);
  const double* z1 = Zcol(2 * a + 1);
  // Its kinetic nodes pull mu_k N_j along e whatever e is, so they leave the cone equation
  // (F_t - mu_k F_n e): the patch's other nodes decide its direction.
  Eigen::Vector3d dF0 = Eigen::Vector3d::Zero(), dF1 = Eigen::Vector3d::Zero(), F_rest = Eigen::Vector3d::Zero();
  for (std::int32_t m = slip_begin_[a]; m < slip_begin_[a + 1]; ++m) {
    const std::int32_t j = slip_members_[m];
    const int k = row_of_[j];
    if (kin_of_[j] >= 0) continue;
    F_rest += f_N_[j];
    if (mode_[j] == ContactMode::kFull3d) {
      dF0 += Eigen::Vector3d(z0[k], z0[k + 1], z0[k + 2]);
      dF1 += Eigen::Vector3d(z1[k], z1[k + 1], z1[k + 2]);
    } else {
      dF0 += z0[k] * n_[j];
      dF1 += z1[k] * n_[j];
    }
  }
  const Eigen::Vector2d slid = SlidOver(a);  // sigma - s
  const Eigen::Vector3d F3 = F_rest + dF0 * slid[0] + dF1 * slid[1];
  const Eigen::Vector2d F_sigma = tangent_[p].transpose() * F3;
  const double N_sigma = -in.n_out.dot(F3);
  Eigen::Matrix2d G;
  G.col(0) = tangent_[p].transpose() * dF0;
  G.col(1) = tangent_[p].transpose() * dF1;
  G = 0.5 * (G + G.transpose()).eval();
  const Eigen::Vector2d h(-in.n_out.dot(dF0), -in.n_out.dot(dF1));
  const double mu = in.mu_kinetic;
  if (!(mu * N_sigma > 0.0)) return 0;  // no pressure: no friction to direct
  if (F_sigma.norm() <= mu * N_sigma) return -1;
  Eigen::Vector2d e = slip_dir_[p];
  double lambda = 0.0, N = N_sigma;
  for (int pass = 0; pass < 4; ++pass) {
    const double c = mu * N;
    if (!(c > 0.0)) break;
    auto inverse_at = [&](double l) -> Eigen::Matrix2d { return (l * G + c * Eigen::Matrix2d::Identity()).inverse(); };
    // Newton from below on |x(l)| = 1 (convex, decreasing for SPD G: never overshoots the root
    // from below); bisection keeps it inside [lo, hi] should G be less than SPD.
    double lo = 0.0, hi = std::numeric_limits<double>::infinity(), l = lambda;
    for (int it = 0; it < 40; ++it) {
      const Eigen::Matrix2d Minv = inverse_at(l);  // one inverse a step, for x and its slope
      const Eigen::Vector2d x = Minv * F_sigma;
      const double f = x.norm() - 1.0;
      if (std::abs(f) <= 1e-13) break;
      if (f > 0.0) lo = l; else hi = l;
      const double df = x.dot(-(Minv * (G * x))) / x.norm();
      double next = df < 0.0 ? l - f / df : lo + 1.0;
      if (!(next > lo && next < hi)) next = std::isfinite(hi) ? 0.5 * (lo + hi) : 2.0 * lo + 1e-9;
      l = next;
    }
    lambda = l;
    const Eigen::Vector2d x = inverse_at(lambda) * F_sigma;
    if (!(x.norm() > 0.0) || !x.allFinite()) break;
    e = x.normalized();
    const double N_next = N_sigma - lambda * h.dot(e);
    if (std::abs(N_next - N) <= 1e-12 * std::abs(N_sigma)) break;
    N = N_next;
  }
  if (!e.allFinite()) return 0;
  if ((e - slip_dir_[p]).norm() <= tol) return 0;
  slip_dir_[p] = e;
  return 1;
}

// The state of SolveWithPatches' rounds: what RestartPass sets at the start of a pass, what a
// pass leaves for the next (frozen_pushed), and the scale of the displacement tests.
struct ContactSolver::PatchRounds {
  PatchRounds(std::int32_t contacts, double imposed_scale) noexcept : pivoting(contacts), d_scale(imposed_scale) {}
  bool refactor = true;
  bool same_columns = false;          // the last round turned directions only
  std::int32_t direction_rounds = 0;  // since the held set last changed (converges in about 6)
  BlockPivoting pivoting;
  std::int32_t pivots = 0, updates = 0;
  bool frozen_pushed = false;  // a let-go node the surface pushes into its tip (last round)
  double d_scale;
};

bool ContactSolver::SolveWithPatches(StepStatus& status) noexcept {
  // Like the general path's iteration, with one more kind of change: a sticking patch whose
  // force leaves its cone starts to slip, in the direction e of that force (and never sticks
  // again within this call; a patch the warm start made slip, RestartPass, is checked once). Patch
  // nodes are held in 3-D; with push_only one that pulls is released and a released one the
  // surface pushes into the tip is held again (at the patch's slide). Other contacts behave as
  // on the general path.
  //
  // A slipping patch's cone equation F_t = mu_k F_n e ties its tangential force to its normal
  // force in a fixed direction (non-associated friction): the held-set problem is no longer
  // symmetric, and pivoting on it can cycle (a node pulls while held and is pressed into the
  // tip while released). When a node comes back a second time, the slipping patches switch to
  // a given tangential force g = mu_k F_n e from the last iterate: for a given g the held set is
  // the solution of a convex problem (pivoting settles it), and g is updated from the new F_n
  // until it no longer changes (a fixed point; the answer satisfies the same equations).
  OrderRowsAsTheFactor();
  ChooseWhichPatchesSettle();
  PatchRounds rounds(num_unique_, ImposedScale());
  // Two passes. The first starts with every node held (patch nodes in 3-D); where push-only
  // nodes pull, the held set it ends in depends on the path the pivoting took, and that path on
  // every candidate, even a patch that ends with no node held: a peer's faded patch losing one
  // such node turned a stick 7 % inside its cone into a slip and a 0.13 N step (docs/fem.md,
  // "Limits"). When a peer's patch ended so, the second pass starts afresh (modes, sticks and
  // slips as given, every other node held) with that patch's nodes released for the whole
  // pass, so the patches that carry force decide. Should the surface then push one of them into
  // its tip, the second pass does not hold, and a third repeats the first. Only peers' patches:
  // a user's own fingertip that lifts off changes what the user feels anyway, and a second pass
  // on every such step cost the friction row of haptic_bench half again at p99.
  std::fill(frozen_.begin(), frozen_.begin() + num_unique_, std::uint8_t{0});
  RestartPass(rounds);
  for (int pass = 0; pass < 3; ++pass) {
    if (pass == 1) {
      if (status == StepStatus::kNotConverged) break;
      if (!FreezeLetGoPeers()) break;
      RestartPass(rounds);
    } else if (pass == 2) {
      // The let-go patches stayed released in the second pass; if the surface now pushes one of
      // their nodes into its tip, that pass's answer does not hold: the first pass again.
      if (!rounds.frozen_pushed && status != StepStatus::kNotConverged) break;
      std::fill(frozen_.begin(), frozen_.begin() + num_unique_, std::uint8_t{0});
      status = StepStatus::kOk;
      RestartPass(rounds);
    }
    if (!RunPatchedPass(rounds, status)) return false;
  }
  MarkKineticPatchesSlipping();
  SumPatchForces();
  return true;
}

bool ContactSolver::RunPatchedPass(PatchRounds& rounds, StepStatus& status) noexcept {
  while (true) {
    if (!SolvePatchedSystem(rounds.refactor, rounds.same_columns)) return false;
    rounds.refactor = false;
    rounds.same_columns = false;
    const double f_scale = ForceScale();
    SumPatchForces();
    if (TurnSlipsTowardTheirSlides(rounds)) continue;
    if (WarmSlipsStickAgain()) {
      ++iterations_;
      continue;
    }
    if (StartSlipping(/*settled=*/false, f_scale)) {
      ++iterations_;
      continue;  // at most one re-solve per patch: slipping does not revert
    }
    bool slipped = false;
    const std::int32_t violations = options_.push_only ? FindPatchedViolations(rounds, f_scale, slipped) : 0;
    if (violations > 0) {
      if (rounds.pivots >= options_.max_active_set_iterations) {
        status = StepStatus::kNotConverged;
        break;
      }
      PivotPatched(rounds, violations, slipped);
      continue;
    }
    if (StartSlipping(/*settled=*/true, f_scale)) {
      ++iterations_;
      rounds.refactor = true;
      rounds.direction_rounds = 0;
      rounds.pivoting = BlockPivoting(num_unique_);
      rounds.pivots = 0;
      continue;
    }
    if (!given_force_) break;
    // The held set is settled for the given forces: update them from the new normal forces.
    if (UpdateGivenForces() <= kTol * f_scale) break;
    if (++rounds.updates > kMaxForceUpdates) {
      status = StepStatus::kNotConverged;
      break;
    }
    ++iterations_;
    rounds.pivoting = BlockPivoting(num_unique_);
    rounds.pivots = 0;
  }
  return true;
}

void ContactSolver::OrderRowsAsTheFactor() noexcept {
  // The held rows' order (perm_): the nodes of the factor in A_ (the last held set factored,
  // this step's or an earlier one's) in its row order, then the new ones, where pivots mostly
  // happen; so the first factor resumes after the rows of the nodes that stayed, and so does a
  // refactor after a pivot.
  std::int32_t q = 0;
  if (fac_valid_) {
    for (std::int32_t j = 0; j < num_unique_; ++j) index_of_slot_[slot_[j]] = j;
    for (std::int32_t k = 0; k < fac_count_; ++k) {
      const std::int32_t j = index_of_slot_[fac_slot_[k]];
      if (j < 0 || in_perm_[j]) continue;
      in_perm_[j] = 1;
      perm_[q++] = j;
    }
    for (std::int32_t j = 0; j < num_unique_; ++j) index_of_slot_[slot_[j]] = -1;
  }
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    if (in_perm_[j]) {
      in_perm_[j] = 0;
    } else {
      perm_[q++] = j;
    }
  }
}

Eigen::Vector2d ContactSolver::MotionAlongSurface(std::int32_t p) const noexcept {
  return tangent_[p].transpose() * patch_in_[p].motion_m;
}

void ContactSolver::ChooseWhichPatchesSettle() noexcept {
  // Which patches decide on the settled held set, with the direction their slide agrees with
  // (found exactly): every patch but one that slipped in the previous step under a fingertip
  // that still moves along the surface, which slips on the way the fingertip moves from the
  // start (a stroke). A sticking patch under a moving fingertip used to be checked on every
  // solve as well, and to take the motion's direction: the first trial holds the nodes that
  // pull, which carry more tangential force than the patch can, so a press or a drag that
  // added a node to a patch 30 % inside its cone slipped it, and its force turned to the
  // motion's in one step (0.49 N at 0.75 N pressing, docs/fem.md, "A sticking patch under a
  // moving fingertip"). Once a call; Settles() asks it every round.
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    settles_[p] = MotionAlongSurface(p).norm() <= kRestMotion_m || !patch_in_[p].slipped_before ? 1 : 0;
  }
}

double ContactSolver::ImposedScale() const noexcept {
  // The scales of the tolerances: the largest imposed displacement or slide (fixed in this call)
  // and, each round, the largest force (ForceScale). A largest norm is the root of the largest
  // squared norm, bit for bit (the root is monotonic and correctly rounded): one root, not one
  // per node.
  double d_scale2 = 0.0;
  for (std::int32_t j = 0; j < num_unique_; ++j) d_scale2 = std::max(d_scale2, d_m_[j].squaredNorm());
  for (std::int32_t p = 0; p < num_patches_; ++p) d_scale2 = std::max(d_scale2, patch_in_[p].slide_m.squaredNorm());
  return d_scale2 == 0.0 ? 1.0 : std::sqrt(d_scale2);
}

double ContactSolver::ForceScale() const noexcept {
  double f_scale2 = 0.0;
  for (std::int32_t j = 0; j < num_unique_; ++j) f_scale2 = std::max(f_scale2, f_N_[j].squaredNorm());
  return f_scale2 == 0.0 ? 1.0 : std::sqrt(f_scale2);
}

void ContactSolver::RestartPass(PatchRounds& rounds) noexcept {
  // A pass starts with every node held but the frozen ones, in the mode its input asks, and every
  // patch at its stick. A patch that slipped in the previous step and whose fingertip still moves
  // along the surface starts slipping, that way: after the first solve WouldStick() checks it
  // against sticking, which the same factor answers, and it sticks if that is inside its cone.
  // (Every other patch starts sticking: a slip's direction then comes from its slide,
  // TurnSlipsTowardTheirSlides.)
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    active_[j] = frozen_[j] ? 0 : 1;
    releases_[j] = 0;
    mode_[j] = mode_in_[j];
    slipping_[j] = 0;
    kin_given_[j].setZero();
  }
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    warm_slip_[p] = Settles(p) ? 0 : 1;
    patch_state_[p].slipping = warm_slip_[p] != 0;
    patch_state_[p].slide_m = patch_in_[p].slide_m;
    if (warm_slip_[p]) slip_dir_[p] = MotionAlongSurface(p).normalized();
  }
  given_force_ = false;
  std::fill(restuck_.begin(), restuck_.end(), std::uint8_t{0});
  rounds.refactor = true;
  rounds.direction_rounds = 0;
  rounds.pivoting = BlockPivoting(num_unique_);
  rounds.pivots = 0;
  rounds.updates = 0;
  rounds.same_columns = false;
}

bool ContactSolver::FreezeLetGoPeers() noexcept {
  // The peers' patches that ended with every node released.
  bool any_let_go = false;
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    if (!patch_in_[p].peer) continue;
    bool holds = false;
    for (std::int32_t j = 0; j < num_unique_ && !holds; ++j) holds = patch_of_[j] == p && active_[j];
    if (holds) continue;
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (patch_of_[j] == p) frozen_[j] = 1;
    }
    any_let_go = true;
  }
  return any_let_go;
}

void ContactSolver::SumPatchForces() noexcept {
  for (std::int32_t p = 0; p < num_patches_; ++p) patch_state_[p].force_N.setZero();
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    if (active_[j] && patch_of_[j] >= 0) patch_state_[patch_of_[j]].force_N += f_N_[j];
  }
}

Eigen::Vector2d ContactSolver::ConeForce(std::int32_t p) const noexcept {
  // The tangential force a slipping patch's cone asks for at its current normal force.
  const double f_n = -patch_in_[p].n_out.dot(patch_state_[p].force_N);
  return patch_in_[p].mu_kinetic * std::max(f_n, 0.0) * slip_dir_[p];
}

bool ContactSolver::TurnSlipsTowardTheirSlides(PatchRounds& rounds) noexcept {
  // A slipping patch (but a stroke's slip carried on): kinetic friction opposes the sliding, so its
  // force runs along the way the fingertip slid over the material, stick - s (tangent
  // coordinates). Holding the trial force's direction instead needs large sideways slides
  // where the patch's tangential stiffness is anisotropic, and a held fingertip crept: its
  // patch changed nodes with every slide and slipped again (docs/fem.md). The direction in
  // which force and slide agree is found per patch (TurnTowardTheSlide); the rounds take the
  // other patches along, with the same factor and columns: only the cone equations change.
  bool turned = false, restuck = false;
  for (std::int32_t a = 0; a < num_slipping_ && !given_force_; ++a) {
    const std::int32_t p = slipping_list_[a];
    if (!Settles(p)) continue;  // a stroke's slip carried on goes the way the fingertip moves
    const int turn = TurnTowardTheSlide(a, 1e-9);
    if (turn > 0) turned = true;
    if (turn < 0 && !restuck_[p]) {  // no direction: held at its stick it is inside its cone
      restuck_[p] = 1;
      patch_state_[p].slipping = false;
      patch_state_[p].slide_m = patch_in_[p].slide_m;
      turned = true;
      restuck = true;
    }
  }
  if (restuck || (turned && rounds.direction_rounds < kMaxDirectionRounds)) {  // a patch stuck again: re-solved
    ++rounds.direction_rounds;
    ++iterations_;
    rounds.same_columns = !restuck;
    return true;
  }
  return false;
}

bool ContactSolver::WarmSlipsStickAgain() noexcept {
  bool sticks_again = false;
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    if (!warm_slip_[p]) continue;
    warm_slip_[p] = 0;
    std::int32_t a = 0;  // its index in the last solve's slipping list (absent: holds no node in 3-D)
    while (a < num_slipping_ && slipping_list_[a] != p) ++a;
    if (a == num_slipping_ || !WouldStick(a)) continue;
    patch_state_[p].slipping = false;
    patch_state_[p].slide_m = patch_in_[p].slide_m;
    sticks_again = true;
  }
  return sticks_again;
}

bool ContactSolver::StartSlipping(bool settled, double f_scale) noexcept {
  // A sticking patch whose force leaves its cone starts to slip, checked once its held set has
  // settled (no node pulls or is pushed in while released); a patch that carries a stroke's slip
  // on (not Settles()) is checked on every solve, as before. A trial with nodes that pull holds
  // more tangential force than the patch can: at rest that slipped a patch every step although
  // the previous step's slide, held, was on its kinetic cone, and it never came to rest; under
  // a moving fingertip it slipped patches well inside their cone (docs/fem.md). Such a patch's
  // nodes then start again held in 3-D: what the sticking trial's pivoting decided about them
  // no longer holds.
  bool any = false;
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    FrictionPatchState& st = patch_state_[p];
    if (st.slipping || Settles(p) != settled) continue;
    const FrictionPatch& in = patch_in_[p];
    const double f_n = -in.n_out.dot(st.force_N);
    const Eigen::Vector2d f_t = tangent_[p].transpose() * st.force_N;
    const double mu = in.slipped_before ? in.mu_kinetic : in.mu_static;
    if (f_t.norm() <= mu * std::max(f_n, 0.0) + kTol * f_scale) continue;
    st.slipping = true;
    // The way it slides: on the settled held set it starts from the trial force's and then
    // follows the slide; a stroke's slip carried on, the fingertip's motion along the surface.
    slip_dir_[p] = settled ? Eigen::Vector2d(f_t / f_t.norm()) : Eigen::Vector2d(MotionAlongSurface(p).normalized());
    slip_force_[p] = ConeForce(p);
    any = true;
    if (!settled) continue;
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (patch_of_[j] != p) continue;
      active_[j] = 1;
      mode_[j] = ContactMode::kFull3d;
      slipping_[j] = 0;
      releases_[j] = 0;
    }
  }
  return any;
}

std::int32_t ContactSolver::FindPatchedViolations(PatchRounds& rounds, double f_scale, bool& slipped) noexcept {
  rounds.frozen_pushed = false;
  ComputeContactDisplacements();
  auto target = [&](std::int32_t j) {
    const std::int32_t p = patch_of_[j];
    return p >= 0 ? Eigen::Vector3d(d_m_[j] + patch_state_[p].slide_m) : d_m_[j];
  };
  // A held node's pull: its normal force (a kinetic node's tangential load is along its patch's
  // surface, not quite its own).
  auto pull = [&](std::int32_t j) {
    const double f = f_N_[j].dot(n_[j]);
    return kin_of_[j] >= 0 ? f - (tangent_[patch_of_[j]] * kin_force_[j]).dot(n_[j]) : f;
  };
  std::int32_t violations = 0;
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    bool v = active_[j] ? pull(j) / f_scale > kTol
                        : (u_c_m_[j] - target(j)).dot(n_[j]) / rounds.d_scale > kTol;
    if (frozen_[j]) {  // stays released in this pass (see SolveWithPatches)
      rounds.frozen_pushed = rounds.frozen_pushed || v;
      v = false;
    }
    violates_[j] = v ? 1 : 0;
    violations += v ? 1 : 0;
    // A sticking contact that pulls slips first, patch node or not (as on the general path:
    // friction needs pressure): it keeps its normal constraint only, for the rest of the call.
    if (v && active_[j] && mode_[j] == ContactMode::kFull3d) {
      mode_[j] = ContactMode::kNormalOnly;
      slipping_[j] = 1;
      kin_given_[j].setZero();
      slipped = true;
    }
  }
  return violations;
}

void ContactSolver::PivotPatched(PatchRounds& rounds, std::int32_t violations, bool slipped) noexcept {
  ++rounds.pivots;
  ++iterations_;
  rounds.refactor = true;       // nodes change held set or mode below (or did: slipped)
  rounds.direction_rounds = 0;  // a new held set: the directions settle again
  MoveViolatorsLast();
  if (slipped) return;
  const bool block = rounds.pivoting.Block(violations);
  for (std::int32_t j = 0; j < num_unique_; ++j) {
    if (!violates_[j]) continue;
    if (active_[j]) {
      active_[j] = 0;
      if (releases_[j] < 255) ++releases_[j];
    } else {
      active_[j] = 1;
      if (mode_[j] == ContactMode::kFull3d) {  // re-engages normal-only (kinetic friction)
        mode_[j] = ContactMode::kNormalOnly;
        slipping_[j] = 1;
        kin_given_[j].setZero();
      }
      if (releases_[j] >= 2 && !given_force_) {  // came back twice: switch (see SolveWithPatches)
        given_force_ = true;
        for (std::int32_t p = 0; p < num_patches_; ++p) {
          if (patch_state_[p].slipping) slip_force_[p] = ConeForce(p);
        }
        for (std::int32_t i = 0; i < num_unique_; ++i) kin_given_[i] = kin_of_[i] >= 0 ? kin_force_[i] : Eigen::Vector2d::Zero();
        rounds.pivoting = BlockPivoting(num_unique_);
        rounds.pivots = 0;
      }
    }
    if (!block) break;  // least index
  }
}

double ContactSolver::UpdateGivenForces() noexcept {
  // The largest change of a slipping patch's given force.
  double change = 0.0;
  for (std::int32_t p = 0; p < num_patches_; ++p) {
    if (!patch_state_[p].slipping) continue;
    const Eigen::Vector2d g = ConeForce(p);
    change = std::max(change, (g - slip_force_[p]).norm());
    slip_force_[p] = g;
  }
  // The kinetic nodes' loads from their normal forces (N_j >= 0).
  for (std::int32_t k = 0; k < num_kinetic_; ++k) {
    const std::int32_t j = kin_list_[k];
    const double y = f_N_[j].dot(n_[j]) - (tangent_[patch_of_[j]] * kin_force_[j]).dot(n_[j]);
    const Eigen::Vector2d g = patch_in_[patch_of_[j]].mu_kinetic * std::max(-y, 0.0) * kin_dir_[k];
    change = std::max(change, (g - kin_given_[j]).norm());
    kin_given_[j] = g;
  }
  return change;
}

void ContactSolver::ComputeContactDisplacements() noexcept {
  // Only a released node's displacement is read (is the surface pushed into the fingertip?): a
  // held node's is the one imposed on it.
  const int ld = 3 * options_.max_contacts;
  for (std::int32_t i = 0; i < num_unique_; ++i) {
    if (active_[i]) continue;
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (!active_[j]) continue;
      Eigen::Map<const Eigen::Matrix3d, 0, Eigen::OuterStride<>> Cij(
          Ccc_.data() + static_cast<std::ptrdiff_t>(3 * j) * ld + 3 * i, 3, 3, Eigen::OuterStride<>(ld));
      u.noalias() += Cij * f_N_[j];
    }
    u_c_m_[i] = u;
  }
}

bool ContactSolver::SurfaceDisplacements(std::span<Eigen::Vector3d> u_m) const noexcept {
  return field_.Evaluate(loads(), u_m);
}

std::int32_t ContactSolver::Displacements(std::span<const std::int32_t> mesh_nodes,
                                          std::span<Eigen::Vector3d> u_m) const noexcept {
  if (mesh_nodes.size() != u_m.size()) return -1;
  const Compliance& C = *compliance_;
  std::int32_t missing = 0;
  for (std::size_t i = 0; i < mesh_nodes.size(); ++i) {
    const std::int32_t v = mesh_nodes[i];
    if (C.IsFixed(v)) {
      u_m[i].setZero();
      continue;
    }
    const std::int32_t n = C.SlotOf(v);
    if (n < 0) {
      u_m[i].setConstant(std::numeric_limits<double>::quiet_NaN());
      ++missing;
      continue;
    }
    Eigen::Vector3d u = Eigen::Vector3d::Zero();
    for (std::int32_t j = 0; j < num_unique_; ++j) {
      if (active_[j]) u.noalias() += C.Block(n, slot_[j]) * f_N_[j];
    }
    u_m[i] = u;
  }
  return missing;
}

}  // namespace handshare::fem
