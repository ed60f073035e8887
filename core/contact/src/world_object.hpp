#pragma once
// The haptic world's objects as its stages see them, in two halves (private to
// handshare::contact's sources: haptic_world.cpp builds them, the stage files step them):
//   HapticModel::Object     what the object is, const once the model is built (collider,
//                           material, mass, compliance, patch finder, friction, beat mode);
//   HapticWorld::ObjectData what it does in one world (pose, velocity, forces, the solver's
//                           state, this step's patches, the remote contacts' memos);
//   HapticWorld::HandData   what the local hand has on the objects (proxies, anchors, results).
#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "handshare/contact/haptic_world.hpp"
#include "handshare/contact/mesh_collider.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_patch.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/mesh.hpp"

namespace handshare::contact {

enum class ObjectKind : std::uint8_t { kStatic, kDynamic, kDeformable };

struct HapticModel::Object {
  ObjectKind kind = ObjectKind::kStatic;
  std::unique_ptr<const MeshCollider> collider;
  RigidMaterial material;
  // Where a world built on this model starts it (HapticWorld::SetPose and SetVelocity move the
  // world's copy, ObjectData).
  Eigen::Isometry3d X_WO0 = Eigen::Isometry3d::Identity();
  Eigen::Vector3d v_W0 = Eigen::Vector3d::Zero(), w_W0 = Eigen::Vector3d::Zero();
  // Dynamic body.
  double mass_kg = 0.0;
  Eigen::Matrix3d I_B = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d I_B_inv = Eigen::Matrix3d::Identity();
  double lin_damp = 0.0, ang_damp = 0.0;
  bool round = false;  // sphere: support acts on the analytic lowest point
  double radius_m = 0.0;
  std::vector<Eigen::Vector3d> support_points_B;
  // Deformable.
  std::shared_ptr<const fem::TetMesh> tet;
  std::shared_ptr<const fem::Compliance> compliance;
  std::unique_ptr<const fem::ContactPatchFinder> patches;
  fem::ContactSolverOptions solver_options;  // sizes each world's solver
  std::int32_t max_patch = 0;
  double mu_static = 0.0, mu_kinetic = 0.0;
  std::shared_ptr<const std::vector<Eigen::Vector3d>> mode;  // per node, frame O; null: none
  std::shared_ptr<const fem::StiffeningTable> stiffening;    // null: the linear force
  double mode_reach_m = 0.0;  // largest |mode|
};

// A remote contact's patch as last found (by its index in the remote list): its query bit for
// bit and the nodes it gave. A peer's contact set changes at the network's rate, not the haptic
// loop's, so most steps ask the same query again and copy the answer.
struct HapticWorld::PatchMemo {
  Eigen::Vector3d p_O_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Vector3d n_O = Eigen::Vector3d::Zero();
  double depth_m = 0.0;
  std::int32_t room = -1;
  std::int32_t count = 0;
  bool truncated = false;
};

struct HapticWorld::ObjectData {
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  Eigen::Vector3d reaction_W_N = Eigen::Vector3d::Zero();  // local fingertips on it, last step
  // Dynamic body.
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero(), w_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d force_W = Eigen::Vector3d::Zero(), torque_W = Eigen::Vector3d::Zero();
  // Deformable.
  std::unique_ptr<fem::ContactSolver> solver;
  std::vector<fem::ContactInput> inputs;
  std::int32_t num_inputs = 0;
  std::vector<fem::FrictionPatch> friction;  // this step's patches (local fingers, then peers')
  std::vector<PatchMemo> remote_memo;
  std::vector<fem::ContactInput> remote_memo_inputs;  // max_patch per memo
  double mode_scale = 0.0;
};

// Per (finger, object): proxy state, previous goal (for the fingertip velocity), and this
// step's contact and force (before the clamp).
struct HapticWorld::FingerObject {
  ProxyState proxy;
  // A moded deformable: where the surface near the fingertip has moved (s mode); the proxy
  // runs on the rest surface toward the fingertip moved back by it.
  Eigen::Vector3d shift_O_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d prev_goal_O_m = Eigen::Vector3d::Zero();
  bool prev_valid = false;
  ProxyContact contact;
  Eigen::Vector3d f_W_N = Eigen::Vector3d::Zero();
  std::int32_t patch_begin = 0, patch_count = 0;
  // Friction on a deformable: the material point the fingertip holds (frame O, on the
  // undeformed surface), whether it holds one, and whether it slipped in the last step.
  Eigen::Vector3d anchor_O_m = Eigen::Vector3d::Zero();
  // The slide the anchor keeps (a slip carried on follows the solved one a quarter of the
  // way) and the slide the last step's solve held (what its report gives peers).
  Eigen::Vector3d slide_O_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d solved_slide_O_m = Eigen::Vector3d::Zero();
  // Where this step's patch was found (the anchor on the contact's tangent plane): peers
  // rebuild it from the contact point a report gives, center + slide (FingerResult::p_WC_m).
  Eigen::Vector3d patch_center_O_m = Eigen::Vector3d::Zero();
  // The fingertip's motion along the surface per step, smoothed (FrictionPatch::motion_m).
  Eigen::Vector3d motion_O_m = Eigen::Vector3d::Zero();
  // The way a slipping patch slides (unit, frame O; zero while it sticks): its force's when it
  // started, turned toward the fingertip's motion a little each step.
  Eigen::Vector3d slip_dir_O = Eigen::Vector3d::Zero();
  bool anchored = false;
  bool slipped = false;
  std::int16_t friction_patch = -1;  // this step's patch index in the solve, -1: none
};

struct HapticWorld::HandData {
  std::vector<FingerObject> fo;  // [finger * num_objects + object]
  std::array<FingerResult, kFingers> results{};
  std::array<double, kFingers> scale{};  // this step's clamp of each finger's force
  FingerObject& at(int finger, std::size_t object, std::size_t num_objects) noexcept {
    return fo[static_cast<std::size_t>(finger) * num_objects + object];
  }
  const FingerObject& at(int finger, std::size_t object, std::size_t num_objects) const noexcept {
    return fo[static_cast<std::size_t>(finger) * num_objects + object];
  }
};

}  // namespace handshare::contact
