// The haptic world's deformable stage: every hand's fingertips on one FEM object in one solve.
// Gather (the local fingers' patches, then the other hands' rebuilt from their contacts, both
// through AddPatch), solve (fem::ContactSolver), apply (each patch's force to its fingertip or
// remote contact, and the friction anchors' next state).
#include <algorithm>
#include <cmath>
#include <limits>

#include "handshare/contact/haptic_world.hpp"
#include "world_object.hpp"

namespace handshare::contact {

void HapticWorld::StepDeformable(const Object& m, ObjectData& d, std::size_t k, std::span<const FingerContact> remote,
                                 StepReport& report) noexcept {
  PatchGather g;
  for (std::size_t r = 0; r < num_remote_forces_; ++r) remote_patch_[r] = {0, 0};
  for (int i = 0; i < kFingers; ++i) GatherLocalPatch(m, d, k, i, g);
  for (std::size_t r = 0; r < remote.size(); ++r) GatherRemotePatch(m, d, k, r, remote[r], g, report);
  d.num_inputs = g.m;
  const fem::StepStatus st = d.solver->Solve(
      std::span<const fem::ContactInput>(d.inputs.data(), static_cast<std::size_t>(g.m)),
      std::span<const fem::FrictionPatch>(d.friction.data(), static_cast<std::size_t>(g.num_friction)));
  const bool failed = st == fem::StepStatus::kInvalidInput || st == fem::StepStatus::kNumericalFailure;
  if (failed) {
    ++report.solver_faults;  // its forces stay zero (the fingers' and the remote contacts')
    return;
  }
  const auto forces = d.solver->forces_N();
  for (std::size_t r = 0; r < num_remote_forces_; ++r) {
    const auto [begin, count] = remote_patch_[r];
    if (count == 0) continue;
    Eigen::Vector3d f_obj = Eigen::Vector3d::Zero();
    for (std::int32_t q = 0; q < count; ++q) f_obj += forces[static_cast<std::size_t>(begin + q)];
    remote_force_O_[r] = PatchGain(m, d, begin, count, forces, remote_n_O_[r], remote_stick_O_[r]) * f_obj;
  }
  for (int i = 0; i < kFingers; ++i) ApplyFingerPatch(m, d, hand_->at(i, k, data_.size()), forces);
}

// The stiffening table's gain of one patch (fem::StiffeningTable::PatchGain): the patch's sum
// is scaled, not each node's force, for neighbouring nodes under a fingertip can carry large
// forces that cancel (docs/fem.md).
double HapticWorld::PatchGain(const Object& m, const ObjectData& d, std::int32_t begin, std::int32_t count,
                              std::span<const Eigen::Vector3d> forces, const Eigen::Vector3d& n_O,
                              const Eigen::Vector3d& stick_O) const noexcept {
  if (!m.stiffening || count <= 0) return 1.0;
  const auto b = static_cast<std::size_t>(begin), n = static_cast<std::size_t>(count);
  return m.stiffening->PatchGain(std::span<const fem::ContactInput>(d.inputs.data() + b, n), forces.subspan(b, n), n_O,
                                 stick_O);
}

// A patch of the fingertip's sphere at p_O along n_O, depth deep, appended to the object's
// inputs. With a memo (a remote contact's), the patch is copied from it while its query is bit
// for bit the same, and found and kept in it otherwise.
void HapticWorld::AddPatch(const Object& m, ObjectData& d, PatchGather& g, const Eigen::Vector3d& p_O,
                           const Eigen::Vector3d& n_O, double depth, std::int32_t& count, bool& truncated,
                           PatchMemo* memo, fem::ContactInput* kept) noexcept {
  const auto cap = static_cast<std::int32_t>(d.inputs.size());
  count = 0;
  const std::int32_t room = std::min(m.max_patch, cap - g.m);
  if (room <= 0 || !(depth > 0.0)) return;
  if (memo != nullptr && memo->room == room && memo->depth_m == depth && memo->p_O_m == p_O && memo->n_O == n_O) {
    std::copy(kept, kept + memo->count, d.inputs.begin() + g.m);
    count = memo->count;
    truncated = memo->truncated;
    g.m += count;
    return;
  }
  const fem::PatchResult pr =
      m.patches->Sphere(p_O, n_O, config().fingertip_radius_m, depth, fem::ContactMode::kNormalOnly,
                        std::span<fem::ContactInput>(d.inputs.data() + g.m, static_cast<std::size_t>(room)));
  count = pr.count;
  truncated = pr.truncated;
  if (memo != nullptr) {
    std::copy(d.inputs.begin() + g.m, d.inputs.begin() + g.m + count, kept);
    *memo = PatchMemo{p_O, n_O, depth, room, count, truncated};
  }
  g.m += pr.count;
}

// Local fingers: the patch under each proxy, pressed to the proxy's depth. With friction the
// fingertip holds the material point it first pressed (its anchor): the patch is centred there
// and slides with the fingertip by the tangential offset (the stick) while the cone holds it;
// the solve says where it slipped to, and the anchor follows.
void HapticWorld::GatherLocalPatch(const Object& m, ObjectData& d, std::size_t k, int i, PatchGather& g) noexcept {
  const bool friction = m.mu_static > 0.0;  // mu_kinetic <= mu_static
  FingerObject& fo = hand_->at(i, k, data_.size());
  fo.patch_begin = g.m;
  fo.patch_count = 0;
  fo.friction_patch = -1;
  if (!fo.contact.touching) {
    fo.anchored = false;
    fo.slipped = false;
    return;
  }
  const Eigen::Vector3d& p = fo.contact.p_O_m;
  const Eigen::Vector3d& n = fo.contact.n_O;
  Eigen::Vector3d stick = Eigen::Vector3d::Zero();
  auto anchor_here = [&] {  // the fingertip holds the material under it now
    fo.anchor_O_m = p;
    fo.slide_O_m.setZero();
    fo.solved_slide_O_m.setZero();
    fo.motion_O_m.setZero();
    fo.anchored = true;
    fo.slipped = false;
  };
  if (friction) {
    if (!fo.anchored) anchor_here();
    const Eigen::Vector3d off = p - fo.anchor_O_m;
    stick = off - off.dot(n) * n;
  }
  bool trunc = false;
  fo.patch_center_O_m = p - stick;
  AddPatch(m, d, g, fo.patch_center_O_m, n, fo.contact.depth_m, fo.patch_count, trunc);
  if (friction && fo.patch_count == 0 && stick.squaredNorm() > 0.0) {
    // No node under the anchor (a slide left it off the fingertip's footprint): without a
    // patch the anchor would never move again and the fingertip would feel nothing while it
    // presses. It holds the material under it now instead.
    anchor_here();
    stick.setZero();
    fo.patch_center_O_m = p;
    AddPatch(m, d, g, p, n, fo.contact.depth_m, fo.patch_count, trunc);
  }
  fo.contact.truncated = fo.contact.truncated || trunc;
  if (!friction || fo.patch_count == 0) return;
  for (std::int32_t q = 0; q < fo.patch_count; ++q) d.inputs[static_cast<std::size_t>(fo.patch_begin + q)].patch = g.num_friction;
  // How the fingertip moves along the surface: this step's motion (stick - last slide),
  // smoothed over about 16 steps. A device held still jitters: the HIRO II model on its plant
  // moves 1.3 um a step (p50; p99 5 um) with no direction kept, which the friction solve took
  // for a stroke (slip decided before its held set settles, docs/fem.md) and the tail under
  // it never came to rest; smoothed, that jitter stays under 0.5 um, a stroke keeps its speed.
  constexpr double kMotionSmoothing = 1.0 / 16.0;
  fo.motion_O_m += kMotionSmoothing * ((stick - fo.slide_O_m) - fo.motion_O_m);
  // A stroke's slip carried on slides the way the solve's FrictionPatch::motion_m says. Right
  // after a slip starts, the material is still springing back from the stick, and the way the
  // fingertip slides over it is the way its force ran when it started (the solve found it),
  // not the way the fingertip moves: on the belly a stick built up across the stroke turned
  // by 90 degrees in the step after the slip started (0.7 N). So the way is carried from the
  // start and turned toward the fingertip's motion by kSlipTurn a step (about 50 ms to follow
  // it), and the solve gets the motion's speed in it.
  Eigen::Vector3d motion = fo.motion_O_m;
  if (fo.slipped && fo.slip_dir_O.squaredNorm() > 0.0) {
    constexpr double kSlipTurn = 0.02;
    const Eigen::Vector3d m_t = motion - motion.dot(n) * n;
    const double speed = m_t.norm();
    const Eigen::Vector3d dir = fo.slip_dir_O - fo.slip_dir_O.dot(n) * n;
    if (speed > 0.0 && dir.squaredNorm() > 0.0) {  // a unit vector plus 2 % of one: never short
      fo.slip_dir_O = (dir.normalized() + kSlipTurn * (m_t / speed)).normalized();
      motion = speed * fo.slip_dir_O;
    }
  }
  d.friction[static_cast<std::size_t>(g.num_friction)] = {n, stick, m.mu_static, m.mu_kinetic, fo.slipped,
                                                        motion, /*peer=*/false};
  fo.friction_patch = g.num_friction++;
}

// Remote fingers: the same patch rebuilt from their contact point, normal and imposed
// displacement. A peer's stick (the part of u along the surface) is held as it sent it while
// the patch's force here stays inside the material's cone (its own solve decided that it
// sticks there, on about the same field); outside it, the patch slips to the cone, afresh
// each step. A peer's patch held as sent whatever its force (the cone it had before) kept
// the whole tangential force while its press faded out, on a node with almost no push left,
// and dropped it in one step when that node let go: 0.063 N (docs/fem.md, "Across the
// network").
// Each remote contact's patch in the inputs (the coupling's force on the body, after the solve).
// The contact is in the body's frame O, as the hand that made it solved it: wherever this
// process has the body (a swimming one is a few milliseconds elsewhere here), the same patch.
void HapticWorld::GatherRemotePatch(const Object& m, ObjectData& d, std::size_t k, std::size_t r,
                                    const FingerContact& rc, PatchGather& g, StepReport& report) noexcept {
  if (rc.object < 0 || static_cast<std::size_t>(rc.object) != k) return;
  const auto p_OC = AsVector(rc.p_OC_m), u_O = AsVector(rc.u_O_m), n_in = AsVector(rc.n_O);
  if (!p_OC.allFinite() || !u_O.allFinite() || !n_in.allFinite() || !(u_O.norm() > 0.0)) {
    ++report.remote_rejected;
    return;
  }
  const double nn = n_in.norm();
  const Eigen::Vector3d n_O = (nn > 0.5 && nn < 2.0) ? Eigen::Vector3d(n_in / nn) : Eigen::Vector3d(-u_O / u_O.norm());
  const double depth = -u_O.dot(n_O);
  if (!(depth > 0.0)) {
    ++report.remote_rejected;  // pulls the surface out: not a press
    return;
  }
  const Eigen::Vector3d stick_O = u_O + depth * n_O;
  const bool sticks = stick_O.norm() > 1e-12 && g.num_friction < static_cast<std::int16_t>(d.friction.size());
  std::int32_t count = 0;
  bool trunc = false;
  const std::int32_t begin = g.m;
  const bool memo = r < kMaxRemoteForces;
  AddPatch(m, d, g, p_OC - (sticks ? stick_O : Eigen::Vector3d::Zero()), n_O, depth, count, trunc,
           memo ? &d.remote_memo[r] : nullptr,
           memo ? d.remote_memo_inputs.data() + r * static_cast<std::size_t>(m.max_patch) : nullptr);
  if (r < kMaxRemoteForces) {
    remote_patch_[r] = {begin, count};
    remote_n_O_[r] = n_O;
    remote_stick_O_[r] = sticks ? stick_O : Eigen::Vector3d::Zero();
  }
  if (!sticks || count == 0) return;
  for (std::int32_t q = 0; q < count; ++q) d.inputs[static_cast<std::size_t>(begin + q)].patch = g.num_friction;
  d.friction[static_cast<std::size_t>(g.num_friction++)] = {n_O, stick_O, m.mu_static, m.mu_kinetic, false,
                                                          Eigen::Vector3d::Zero(), /*peer=*/true};
}

// A local fingertip's share of the solve: the force its patch puts on the object, felt as minus
// that, and with friction where its anchor goes next.
void HapticWorld::ApplyFingerPatch(const Object& m, ObjectData& d, FingerObject& fo,
                                   std::span<const Eigen::Vector3d> forces) noexcept {
  if (!fo.contact.touching) return;
  Eigen::Vector3d f_obj = Eigen::Vector3d::Zero();
  for (std::int32_t q = 0; q < fo.patch_count; ++q) f_obj += forces[static_cast<std::size_t>(fo.patch_begin + q)];
  if (m.stiffening) {
    const Eigen::Vector3d stick =
        fo.friction_patch >= 0 ? d.solver->patch_states()[static_cast<std::size_t>(fo.friction_patch)].slide_m
                               : Eigen::Vector3d::Zero();
    f_obj *= PatchGain(m, d, fo.patch_begin, fo.patch_count, forces, fo.contact.n_O, stick);
  }
  fo.f_W_N = -(d.X_WO.linear() * f_obj);  // the fingertip feels minus the force on the object
  if (fo.friction_patch >= 0) {
    const fem::FrictionPatchState& ps = d.solver->patch_states()[static_cast<std::size_t>(fo.friction_patch)];
    if (ps.slipping && !fo.slipped) {  // the way it starts to slide: its force's
      const Eigen::Vector3d& n = fo.contact.n_O;
      const Eigen::Vector3d ft = ps.force_N - ps.force_N.dot(n) * n;
      fo.slip_dir_O = ft.squaredNorm() > 0.0 ? Eigen::Vector3d(ft.normalized()) : Eigen::Vector3d::Zero();
    } else if (!ps.slipping) {
      fo.slip_dir_O.setZero();
    }
    // The slide a peer rebuilds this step's patch with is the one solved. The anchor the next
    // step starts from follows a slip carried on a quarter of the way: where a few nodes hold
    // a patch (the belly's 1-4), the slide solved on one held set moves the patch onto
    // another, whose slide moves it back: the anchor swung 0.6-1.5 mm every step and the
    // force with it, growing, for as long as the slip lasted. A quarter damps a swing whose
    // gain is up to 7 (half way left the belly's worst stroke humming for 30 steps, a fifth
    // of the way kept a tail held still from coming to rest); a steady slide is reached as
    // before, the anchor lagging it by about three steps (60 um at 20 mm/s).
    fo.solved_slide_O_m = ps.slide_m;
    constexpr double kSlideFollow = 0.25;
    if (ps.slipping && fo.slipped) {
      fo.slide_O_m += kSlideFollow * (ps.slide_m - fo.slide_O_m);
    } else {
      fo.slide_O_m = ps.slide_m;
    }
    fo.slipped = ps.slipping;
    fo.anchor_O_m = fo.contact.p_O_m - fo.slide_O_m;
  }
}

}  // namespace handshare::contact
