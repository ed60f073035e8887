#pragma once
// The haptic world's objects as its stages see them (private to handshare::contact's sources:
// haptic_world.cpp sets them up, the stage files step them).
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

enum class ObjectKind : std::uint8_t { kStatic, kDynamic, kDeformable };

struct HapticWorld::Object {
  ObjectKind kind = ObjectKind::kStatic;
  std::unique_ptr<MeshCollider> collider;
  RigidMaterial material;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  Eigen::Vector3d reaction_W_N = Eigen::Vector3d::Zero();  // local fingertips on it, last step
  // Dynamic body.
  double mass_kg = 0.0;
  Eigen::Matrix3d I_B = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d I_B_inv = Eigen::Matrix3d::Identity();
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero(), w_W = Eigen::Vector3d::Zero();
  double lin_damp = 0.0, ang_damp = 0.0;
  Eigen::Vector3d force_W = Eigen::Vector3d::Zero(), torque_W = Eigen::Vector3d::Zero();
  bool round = false;  // sphere: support acts on the analytic lowest point
  double radius_m = 0.0;
  std::vector<Eigen::Vector3d> support_points_B;
  // Deformable.
  std::shared_ptr<const fem::TetMesh> tet;
  std::shared_ptr<const fem::Compliance> compliance;
  std::unique_ptr<fem::ContactPatchFinder> patches;
  std::unique_ptr<fem::ContactSolver> solver;
  std::vector<fem::ContactInput> inputs;
  std::int32_t num_inputs = 0;
  std::int32_t max_patch = 0;
  double mu_static = 0.0, mu_kinetic = 0.0;
  std::vector<fem::FrictionPatch> friction;  // this step's patches (local fingers, then peers')
  std::vector<PatchMemo> remote_memo;
  std::vector<fem::ContactInput> remote_memo_inputs;  // max_patch per memo
  std::shared_ptr<const std::vector<Eigen::Vector3d>> mode;  // per node, frame O; null: none
  double mode_reach_m = 0.0;  // largest |mode|
  double mode_scale = 0.0;
};

}  // namespace handshare::contact
