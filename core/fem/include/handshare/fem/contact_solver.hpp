#pragma once
/// @file
/// Real-time contact solve on a precomputed Compliance (the symmetric compliance form of the
/// elementary displacement method, see docs/fem.md):
///   solve (G C_cc G^T + eps I) lambda = G d*,  f = G^T lambda           (contact forces)
///   u_n = sum_j C_n,kj f_j                                               (surface field)
/// where c are the touched nodes, d* their imposed displacements and G selects all three
/// components (sticking contact) or the normal one (frictionless). This is the exact static FEM
/// solution with the touched nodes held at d* (Schur complement identity). The force path costs
/// O(m^3) for m contacts, independent of the mesh size; the surface field costs O(N m).
///
/// Coulomb friction of a fingertip patch (FrictionPatch): the patch's held nodes are imposed in
/// full 3-D (the paper's elementary displacements) and slide together by one tangential
/// displacement s, the patch's stick. While the tangential force on the patch stays inside the
/// cone |F_t| <= mu F_n the patch sticks (s as given); outside it the patch slips: s becomes
/// two unknowns and two equations put the force on the cone, F_t = mu_k F_n e, in the direction
/// e in which the force and the slide agree (a stroke's slip carried on: the way the fingertip
/// moves), checked once the push-only held set has settled. Both states are
/// linear solves on C_cc, so each is the exact static FEM solution for its displacements;
/// docs/fem.md ("Friction") gives the equations. A patch whose held nodes all pulled when held in
/// 3-D (kept along their normal only) gives them kinetic friction mu_k N_j along its slip or its
/// fingertip's motion, solved exactly with the slides (docs/fem.md, "Kinetic friction on nodes
/// held along their normal"); it then slips.
/// Solve() and the displacement queries are noexcept and do not allocate: everything is sized by
/// the constructor for ContactSolverOptions::max_contacts.

#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "handshare/fem/compliance.hpp"
#include "handshare/fem/surface_field.hpp"

namespace handshare::fem {

/// How a touched node is held.
enum class ContactMode : std::uint8_t {
  kFull3d,      ///< all three components imposed (sticking fingertip).
  kNormalOnly,  ///< only n_out . u imposed; tangential motion free (frictionless).
};

/// One touched node. Plain data, trivially copyable.
struct ContactInput {
  std::int32_t node = -1;                                  ///< mesh node index.
  Eigen::Vector3d u_m = Eigen::Vector3d::Zero();           ///< imposed displacement [m].
  Eigen::Vector3d n_out = Eigen::Vector3d::Zero();         ///< unit outward normal (push-only,
                                                           ///< kNormalOnly); zero = none.
  ContactMode mode = ContactMode::kFull3d;
  /// Index of the FrictionPatch this node belongs to (Solve()'s `patches`), or -1 for none. A
  /// patch node is held in full 3-D at u_m plus the patch's slide (mode is ignored); u_m is then
  /// the normal part only. A node touched by several inputs takes the first input's patch.
  std::int16_t patch = -1;
};

/// One fingertip patch with Coulomb friction: the nodes whose ContactInput::patch names it.
struct FrictionPatch {
  Eigen::Vector3d n_out = Eigen::Vector3d::Zero();    ///< unit outward normal (the cone's axis).
  Eigen::Vector3d slide_m = Eigen::Vector3d::Zero();  ///< the stick: tangential displacement the
                                                      ///< patch's nodes take while it sticks [m]
                                                      ///< (its normal part is ignored).
  double mu_static = 0.0;    ///< the patch sticks while |F_t| <= mu_static F_n ...
  double mu_kinetic = 0.0;   ///< ... and slips with |F_t| = mu_kinetic F_n.
  bool slipped_before = false;  ///< slipping in the previous step: it sticks again only once
                                ///< |F_t| <= mu_kinetic F_n.
  /// How the fingertip moves along the surface per step (the stick minus the last slide;
  /// HapticWorld smooths it over about 16 steps, so a device's jitter is no motion) [m]. A patch
  /// that slipped_before under a fingertip moving 1 um a step or more carries its slip on this
  /// way (kinetic friction opposes the sliding: a stroke). Any other patch is checked against
  /// its cone once the held set has settled and slips the way the fingertip slid over the
  /// material, stick minus slide, found in a few rounds from the sticking trial force's.
  Eigen::Vector3d motion_m = Eigen::Vector3d::Zero();
  /// A peer's fingertip (its stick as its contact set sent it). When every node of a peer's patch ends
  /// released, the call solves again with that patch released from the start: a patch that
  /// carries nothing then cannot decide, by the path of the pivoting, how the others hold.
  bool peer = false;
};

/// What became of a FrictionPatch in the last Solve().
struct FrictionPatchState {
  bool slipping = false;                              ///< slid to the cone's surface.
  Eigen::Vector3d slide_m = Eigen::Vector3d::Zero();  ///< the tangential displacement held: the
                                                      ///< given stick, or where it slipped to.
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();  ///< sum of its nodes' forces on the object.
};

/// What became of one input contact.
enum class ContactState : std::uint8_t {
  kActive,               ///< held as requested; carries force.
  kSlipping,             ///< push-only: a sticking contact that would pull cannot hold
                         ///< friction, so it slips (held along n_out only); or a node of a
                         ///< FrictionPatch that slips (held in 3-D at the slid position).
  kReleased,             ///< push-only: would pull, so released (zero force).
  kRejectedFixed,        ///< the node is fixed: ignored (zero force).
  kRejectedUnknownNode,  ///< not a compliance node (interior, out of range): ignored.
  kRejectedInvalid,      ///< NaN/Inf, or no usable normal where one is needed (the whole
                         ///< step then returns kInvalidInput).
};

/// Outcome of a Solve() call.
enum class StepStatus : std::uint8_t {
  kOk,
  kSomeRejected,      ///< solved; some contacts were rejected (see states()), or there were
                      ///< more than max_contacts inputs and only the first max_contacts
                      ///< were used (forces_N() and states() cover only those).
  kInvalidInput,      ///< NaN/Inf displacement or normal, or a zero normal where one is needed:
                      ///< all forces set to zero.
  kNotConverged,      ///< push-only active set hit its iteration cap: last iterate returned.
  kNumericalFailure,  ///< Cholesky of the contact matrix failed: all forces set to zero.
};

/// Options, fixed at construction.
struct ContactSolverOptions {
  /// Most contacts (touched nodes, before merging) one Solve() accepts; sizes all buffers.
  std::int32_t max_contacts = 15;
  /// Tikhonov regularization eps [m/N]: (C_cc + eps I) f = d*. 0 = exact.
  double regularization_m_per_N = 0.0;
  /// Virtual coupling stiffness k_c [N/m]: (C_cc + I / k_c) f = d* (a spring between the
  /// fingertip proxy and the node). 0 = off. Adds to regularization_m_per_N.
  double coupling_stiffness_N_per_m = 0.0;
  /// Unilateral contact, needs n_out on every contact. A frictionless contact that would pull
  /// (f . n_out > 0) is released; a sticking one first slips (friction needs pressure, so it
  /// keeps only its normal constraint), then is released if it still pulls. A released node the
  /// surface would push into the fingertip is re-engaged (frictionless). Sticking contacts that
  /// push hold any tangential force (no friction cone).
  bool push_only = false;
  /// Cap on active-set changes per Solve() when push_only.
  std::int32_t max_active_set_iterations = 64;
  /// Most FrictionPatches one Solve() accepts; sizes the buffers of the friction solve.
  std::int32_t max_friction_patches = 16;
};

/// The real-time contact solver. Not thread-safe; one per haptic thread and object.
class ContactSolver {
 public:
  /// Allocates every buffer for options.max_contacts (the Init of the real-time rules).
  /// @throws InputError for a null compliance or bad options.
  ContactSolver(std::shared_ptr<const Compliance> compliance, const ContactSolverOptions& options);

  /// Solves for the given touched nodes. Nodes touched more than once are merged (mean imposed
  /// displacement; the node's force is split evenly between the inputs). Fixed and unknown nodes
  /// are rejected, not thrown. Real-time: noexcept, no allocation, O(m^3).
  /// Push-only with every contact frictionless (fingertip patches) is solved as the m x m
  /// problem on n_i^T C_ij n_j, started from the previous call's held set and with the blocks
  /// of nodes touched in consecutive calls kept from it: faster, same answer (the problem has
  /// one solution), so the result does not depend on the call history.
  StepStatus Solve(std::span<const ContactInput> contacts) noexcept { return Solve(contacts, {}); }
  /// The same with Coulomb friction on the patches that contacts name (see FrictionPatch): a
  /// stick whose force leaves the cone slips; slipping never reverts within one call, so the
  /// patches add at most patches.size() re-solves to the push-only iterations. A contact that
  /// names a patch out of range, or a patch with a bad normal, slide or mu, is invalid input.
  /// Real-time: noexcept, no allocation.
  StepStatus Solve(std::span<const ContactInput> contacts,
                   std::span<const FrictionPatch> patches) noexcept;
  /// The patches of the last Solve(), same order as given.
  std::span<const FrictionPatchState> patch_states() const noexcept {
    return {patch_state_.data(), static_cast<std::size_t>(num_patches_)};
  }

  /// Force on the object at each input contact [N] (push: along -n_out), same order as the
  /// inputs of the last Solve().
  std::span<const Eigen::Vector3d> forces_N() const noexcept {
    return {forces_N_.data(), static_cast<std::size_t>(num_inputs_)};
  }
  std::span<const ContactState> states() const noexcept {
    return {states_.data(), static_cast<std::size_t>(num_inputs_)};
  }
  /// Sum of all contact forces on the object [N].
  Eigen::Vector3d total_force_N() const noexcept;
  /// Distinct touched nodes in the last Solve() and how many of them are held.
  std::int32_t num_unique() const noexcept { return num_unique_; }
  std::int32_t num_active() const noexcept;
  /// Active-set changes in the last Solve().
  std::int32_t active_set_iterations() const noexcept { return iterations_; }

  /// The held nodes' loads of the last Solve() (one per distinct active node): hand these to a
  /// SurfaceField on the graphics thread to get the surface field there.
  std::span<const NodeLoad> loads() const noexcept {
    return {loads_.data(), static_cast<std::size_t>(num_loads_)};
  }

  /// Displacement [m] of every compliance node (slot order) for the last Solve(): O(N m), see
  /// SurfaceField. u_m.size() must be num_nodes(); returns false (and writes nothing) otherwise.
  /// Uses scratch memory of this solver: call it from the thread that calls Solve().
  bool SurfaceDisplacements(std::span<Eigen::Vector3d> u_m) const noexcept;
  /// Displacement [m] of the given mesh nodes (e.g. the visible ones). Fixed nodes get 0; nodes
  /// that are not compliance nodes get NaN. Returns the number of NaN entries, or -1 if the
  /// sizes differ.
  std::int32_t Displacements(std::span<const std::int32_t> mesh_nodes,
                             std::span<Eigen::Vector3d> u_m) const noexcept;

  const Compliance& compliance() const noexcept { return *compliance_; }
  const ContactSolverOptions& options() const noexcept { return options_; }

 private:
  // The state of SolveWithPatches' rounds in a pass (defined in contact_solver.cpp).
  struct PatchRounds;

  // Construction: throws InputError for bad options; sizes every buffer.
  void CheckOptions() const;
  void AllocateContactBuffers();
  void AllocatePatchBuffers();

  // Solve()'s stages. The patches' inputs and tangent bases; false if one is bad.
  bool ReadPatches(std::span<const FrictionPatch> patches) noexcept;
  // Stage 1: validates the inputs (invalid: the call fails; rejected: ignored) and merges the
  // touches of one node; then their mean displacement and normal (false: opposite normals).
  void MergeTouches(std::span<const ContactInput> contacts, bool& invalid, bool& rejected) noexcept;
  bool AverageMergedTouches() noexcept;
  // Stages 2 and 3: the compliance of the touched nodes and the solve of the path they need.
  // Returns false on a numerical failure.
  bool GatherAndSolve(StepStatus& status) noexcept;
  // Stage 4: forces_N_, states_ and loads_ from the solved nodes.
  void WriteOutputs() noexcept;
  // Zero outputs, nothing kept for the next call: returns status.
  StepStatus GiveUp(StepStatus status) noexcept;

  // The general path: any modes, no patches; with push_only, pivoting on the held set.
  bool SolveGeneral(StepStatus& status) noexcept;
  bool SolveActiveSet() noexcept;
  // Fills rhs_ = G d* and row_of_ for the held contacts, rows in the order perm_ lists the nodes,
  // and, with fill_matrix, A_ = G C_cc G^T (its lower triangle; only the rows from from_row on,
  // for a factor resumed there); returns the row count.
  int AssembleHeld(bool fill_matrix, int from_row = 0) noexcept;
  // The rows of the held set (in perm_ order, with their modes) that are those of the factor in
  // A_ (fac_*), so that a refactor resumes after them; 0 where none are, or it cannot resume.
  int ResumableRows() const noexcept;
  void MoveViolatorsLast() noexcept;
  void RememberFactored() noexcept;
  // f_N_ of the held contacts from the solved rows in rhs_; false if one is not finite.
  bool ForcesFromRows() noexcept;
  // u_c_m_ of the released nodes: C_cc f from the held ones.
  void ComputeContactDisplacements() noexcept;

  // Push-only or not, with the friction patches (every patch node held in 3-D). Returns false on
  // a numerical failure.
  bool SolveWithPatches(StepStatus& status) noexcept;
  // One pass of SolveWithPatches: rounds of solves and changes until none is left.
  bool RunPatchedPass(PatchRounds& rounds, StepStatus& status) noexcept;
  // SolveWithPatches' stages: perm_ from the kept factor's rows; settles_; the scale of the
  // imposed displacements and of the forces; a pass's start; the peers' patches that let go
  // (frozen_ for the next pass; false if none).
  void OrderRowsAsTheFactor() noexcept;
  void ChooseWhichPatchesSettle() noexcept;
  double ImposedScale() const noexcept;
  double ForceScale() const noexcept;
  void RestartPass(PatchRounds& rounds) noexcept;
  bool FreezeLetGoPeers() noexcept;
  // A round's changes, in the order they are tried; each true if it changed something to solve
  // again: slipping patches turned toward their slides, patches the warm start made slip that
  // stick, sticking patches outside their cones that slip.
  bool TurnSlipsTowardTheirSlides(PatchRounds& rounds) noexcept;
  bool WarmSlipsStickAgain() noexcept;
  bool StartSlipping(bool settled, double f_scale) noexcept;
  // Push-only: violates_ (held nodes that pull, released ones pressed into their tips) and the
  // sticking ones that slip (slipped); returns the count. Then the pivot on them.
  std::int32_t FindPatchedViolations(PatchRounds& rounds, double f_scale, bool& slipped) noexcept;
  void PivotPatched(PatchRounds& rounds, std::int32_t violations, bool slipped) noexcept;
  // The slipping patches' given forces from their cones; returns the largest change.
  double UpdateGivenForces() noexcept;
  // patch_state_'s forces from f_N_; a patch's cone force; whether it decides on the settled
  // held set; the fingertip's motion along the surface (tangent coordinates).
  void SumPatchForces() noexcept;
  Eigen::Vector2d ConeForce(std::int32_t p) const noexcept;
  bool Settles(std::int32_t p) const noexcept { return settles_[p] != 0; }
  Eigen::Vector2d MotionAlongSurface(std::int32_t p) const noexcept;
  // One linear solve of SolveWithPatches at the current held set and patch states: f_N_, and
  // the slipping patches' slides. refactor: the held set or a node's mode changed since the
  // last call (else A_ still holds the factor of G C_cc G^T). Returns false on a numerical
  // failure.
  bool SolvePatchedSystem(bool refactor, bool same_columns = false) noexcept;
  // Its stages: the sticking patches' slides into rhs_; the factor of the r held rows (resumed
  // after p0); the slipping patches' members and cone weights; z0 and Z; the slides (false: not
  // finite, or a singular system).
  void AddSticks() noexcept;
  bool FactorHeld(int r, int p0) noexcept;
  void ListSlippingPatches() noexcept;
  void SolveColumns(int r, bool same_columns) noexcept;
  bool SolveSlides(int r) noexcept;
  // For a patch the warm start made slip (list index a of the last SolvePatchedSystem): true if
  // held at its stick instead it would be inside its cone (the forces from z0 + Z s, no solve).
  bool WouldStick(std::int32_t a) const noexcept;
  // For list index a of the last SolvePatchedSystem: its direction set to the one in which its
  // force and its slide agree (exact for the patch, the others' slides held); 1 if that turned
  // it by more than tol, 0 if not, -1 if held at its stick it would be inside its cone.
  int TurnTowardTheSlide(std::int32_t a, double tol) noexcept;
  // For list index a of the last SolvePatchedSystem: how far its fingertip slid over the
  // material, the stick minus the slide it solved (tangent coordinates).
  Eigen::Vector2d SlidOver(std::int32_t a) const noexcept;
  // Kinetic friction on the patch nodes held along their normal only (they pulled when held in
  // 3-D): the way patch p's such nodes drag the body (tangent coordinates; zero: none), the
  // list of them in this solve (kin_list_) and their tangential loads' columns.
  Eigen::Vector2d KineticDirection(std::int32_t p) const noexcept;
  void ListKineticNodes() noexcept;
  void KineticColumns(int r) noexcept;
  // Patches left with no node held in 3-D but kinetic ones: they slide (slipping, at the stick).
  void MarkKineticPatchesSlipping() noexcept;

  // Push-only with every contact frictionless: the scalar problem on S = N^T C_cc N, warm
  // started from the previous Solve()'s active set. Returns false on a numerical failure.
  bool SolveNormalPushOnly(StepStatus& status) noexcept;
  void WarmStartActiveSet() noexcept;
  // Its stages: act_ and act_pos_ of the held nodes (returns their count r); lambda_N_ of the r
  // held ones (false on a numerical failure); violates_ and their count.
  std::int32_t ListActiveNormals() noexcept;
  bool SolveActiveNormals(std::int32_t r) noexcept;
  std::int32_t FindNormalViolations(std::int32_t r, double d_scale) noexcept;
  // Fills S_ for slot_[0..num_unique_) at their table positions, reading only blocks the table
  // lacks and computing only the entries of nodes that are new or whose normal changed.
  void GatherNormalCompliance() noexcept;
  // Its stages: pos_ and is_new_ (a node touched in the previous Solve() keeps its position);
  // a prefetch of the new pairs' blocks; the table and S_ entries of new or turned nodes.
  void AssignTablePositions() noexcept;
  void PrefetchNewBlocks() const noexcept;
  void FillNormalCompliance() noexcept;
  void RememberActiveSet() noexcept;
  // Drops the previous Solve()'s nodes (no warm start, no table positions carried over).
  void ForgetPrevious() noexcept;
  void ZeroOutputs() noexcept;

  std::shared_ptr<const Compliance> compliance_;
  ContactSolverOptions options_;
  double eps_m_per_N_ = 0.0;

  std::int32_t num_inputs_ = 0;
  std::int32_t num_unique_ = 0;
  std::int32_t iterations_ = 0;

  // Per input contact.
  std::vector<Eigen::Vector3d> forces_N_;
  std::vector<ContactState> states_;
  std::vector<std::int32_t> unique_of_input_;
  // Per unique node.
  std::vector<std::int32_t> slot_;
  std::vector<std::int32_t> multiplicity_;
  std::vector<Eigen::Vector3d> d_m_;
  std::vector<Eigen::Vector3d> n_;
  std::vector<ContactMode> mode_;
  std::vector<ContactMode> mode_in_;  // as the inputs ask (patch nodes in 3-D)
  std::vector<std::uint8_t> frozen_;  // released for a whole pass of SolveWithPatches
  std::vector<std::uint8_t> active_;
  std::vector<std::uint8_t> slipping_;
  std::vector<Eigen::Vector3d> f_N_;
  std::vector<Eigen::Vector3d> u_c_m_;
  // Dense work: C_cc (3M x 3M), the reduced matrix and its factor, right-hand side.
  std::vector<double> Ccc_;
  std::vector<double> A_;
  std::vector<double> rhs_;
  std::vector<std::int32_t> row_of_;
  std::vector<NodeLoad> loads_;
  std::int32_t num_loads_ = 0;
  // Scalar (frictionless) path: S (M x M, ld M) indexed by table positions (pos_: entry
  // (pos_[i], pos_[j]) is n_i^T C_ij n_j, kept between Solve()s like the block table), its
  // factor on the active rows (compact, ld r), normal forces lambda (f = lambda n), normal
  // gaps, active indices and their table positions.
  std::vector<double> S_;
  std::vector<double> L_;
  std::vector<double> lambda_N_;
  std::vector<double> dn_m_;
  std::vector<std::int32_t> act_;
  std::vector<std::int32_t> act_pos_;
  std::vector<std::uint8_t> violates_;
  // Per compliance slot: its distinct node's index while Stage 1 merges touches, and its index
  // in the previous Solve() (-1: none), so that neither is a search over the nodes.
  std::vector<std::int32_t> index_of_slot_;
  std::vector<std::int32_t> prev_of_slot_;
  // The previous Solve()'s distinct nodes and which were held (warm start).
  std::vector<std::int32_t> prev_slot_;
  std::vector<std::uint8_t> prev_active_;
  // The order of the held rows (node indices): identity, except with friction patches, where the
  // nodes of the factor in A_ come first, in its row order, and the others (new ones) after
  // them; a pivot moves the nodes it found violating to the end (MoveViolatorsLast). A factor's
  // rows are those of the held set that stayed, then the ones a pivot changed,
  // so a refactor after the next pivot, or the next step's first factor, resumes after the rows
  // that stayed (ResumeFactorSpd): their block of G C_cc G^T is the same numbers (the same
  // compliance blocks, normals and regularization). fac_*: the held nodes of the factor in A_
  // in row order, by compliance slot, whether in 3-D, and the normal of the others.
  std::vector<std::int32_t> perm_;
  std::vector<std::int32_t> perm_scratch_;
  std::vector<std::uint8_t> in_perm_;
  std::vector<std::int32_t> fac_slot_;
  std::vector<std::uint8_t> fac_full3d_;
  std::vector<Eigen::Vector3d> fac_n_;
  std::int32_t fac_count_ = 0;
  bool fac_valid_ = false;
  std::vector<std::int32_t> prev_index_;  // per distinct node: its index in the previous Solve()
  // Block table of the scalar path: C_ab of table positions a <= b (packed, 3x3 column-major
  // each); the position of each distinct node, of the previous Solve()'s nodes, free positions.
  std::vector<double> table_;
  std::vector<std::int32_t> pos_;
  std::vector<std::uint8_t> is_new_;
  std::vector<std::int32_t> prev_pos_;
  std::vector<std::uint8_t> prev_kept_;
  std::vector<std::int32_t> free_pos_;
  // The normal each position had when its S_ entries were computed: a pair of old nodes whose
  // normals are bit for bit the same keeps its S_ entry.
  std::vector<Eigen::Vector3d> pos_n_;
  std::vector<std::uint8_t> same_n_;
  std::int32_t num_free_ = 0;
  bool table_valid_ = false;
  std::int32_t num_prev_ = 0;
  // Friction patches: per distinct node its patch (-1: none); per patch the input, its tangent
  // basis (3x2), the direction it slips in (tangent coordinates) and the result; the slipping
  // patches' response columns (Z_, below) and their 2P x 2P system.
  std::vector<std::int16_t> patch_of_;
  std::vector<std::uint8_t> releases_;  // per distinct node: times released in this Solve()
  std::vector<FrictionPatch> patch_in_;
  std::vector<Eigen::Matrix<double, 3, 2>> tangent_;
  std::vector<Eigen::Vector2d> slip_dir_;
  std::vector<Eigen::Vector2d> slip_force_;  // the given tangential force (given_force_)
  std::vector<std::uint8_t> warm_slip_;      // slipping by the warm start, not yet checked
  std::vector<std::uint8_t> settles_;  // decides on the settled held set (not a stroke carried on)
  std::vector<std::uint8_t> restuck_;  // stuck again this call because no direction agreed
  bool given_force_ = false;
  std::vector<FrictionPatchState> patch_state_;
  std::vector<std::int32_t> slipping_list_;
  std::int32_t num_slipping_ = 0;  // in slipping_list_, as the last SolvePatchedSystem left it
  int patched_rows_ = 0;           // the held rows of the last SolvePatchedSystem
  // z0 (column 0) and the slipping patches' columns Z = A^-1 B (3M x (1 + 2P), ld 3M).
  std::vector<double> Z_;
  double* Zcol(int col) noexcept { return Z_.data() + static_cast<std::ptrdiff_t>(1 + col) * 3 * options_.max_contacts; }
  const double* Zcol(int col) const noexcept {
    return Z_.data() + static_cast<std::ptrdiff_t>(1 + col) * 3 * options_.max_contacts;
  }
  std::vector<double> slip_M_;
  std::vector<double> slip_rhs_;
  std::vector<std::int32_t> slip_piv_;
  // The cone equations (SolvePatchedSystem): per slipping patch its nodes (members from
  // slip_begin_[a] to slip_begin_[a + 1]), and the held rows it reads (from slip_row_begin_[a])
  // with their weights in its two equations, so Phi applies with one read per row.
  std::vector<std::int32_t> slip_members_;
  std::vector<std::int32_t> slip_begin_;
  std::vector<std::int32_t> slip_row_;
  std::vector<std::int32_t> slip_row_begin_;
  std::vector<double> slip_row_w0_, slip_row_w1_;
  std::vector<double> slip_sum_;  // a patch's two sums over every column
  // Kinetic friction on the patch nodes held normal-only (KineticDirection): the nodes in the
  // last SolvePatchedSystem (at most max_kinetic_; their unknown tangential loads g, two each,
  // follow the slides in Z_'s columns and in the system), per distinct node its index in that
  // list (-1: none), the tangential load solved and the load given (given_force_; tangent
  // coordinates of its patch), and per listed node the way it drags.
  std::vector<std::int32_t> kin_list_;
  std::vector<std::int32_t> kin_of_;
  std::vector<Eigen::Vector2d> kin_force_;
  std::vector<Eigen::Vector2d> kin_given_;
  std::vector<Eigen::Vector2d> kin_dir_;
  std::int32_t num_kinetic_ = 0;
  std::int32_t max_kinetic_ = 0;
  std::int32_t num_patches_ = 0;
  mutable SurfaceField field_;
};

}  // namespace handshare::fem
