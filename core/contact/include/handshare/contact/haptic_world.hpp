#pragma once
/// @file
/// Haptic rendering of one hand (5 fingertips) against a scene of static rigid objects, dynamic
/// rigid bodies (grasping, under the scene's gravity) and FEM deformables shared with remote
/// hands. Layer 4 of the architecture (haptic rendering): no middleware, no rendering.
///
/// Model and data (as MuJoCo's mjModel/mjData, Pinocchio's Model/Data): a HapticModel is what
/// the scene's objects are (colliders, materials, masses, compliances, beat modes, the support
/// and gravity), const once built; a HapticWorld steps its own data on one (poses, velocities,
/// forces, the deformables' solver state and patch memos, and per hand the proxies, friction
/// anchors and results). Any number of worlds may share one model (shared_model()).
///
/// Setup (allocates, may throw): construct with a WorldConfig, Add*() objects, SetSupport(),
/// then Init() freezes the model and sizes every per-step buffer for config.max_hands x kFingers
/// fingertips; or construct on a model another world built (HapticWorld(shared_model())).
/// Real time: Step() is noexcept and never allocates; it reads the local fingertip centres and
/// the remote hands' contacts and writes one FingerResult per local finger.
///
/// Per step, for each local finger and object (object frame O; the proxy lives in O, so it
/// moves with a dynamic body):
///   collision + proxy (proxy.hpp) -> contact point, normal n, penetration vector e = p_E - p_P
///   rigid:      f_E = -k e - b (v_E . n) n, proxy friction (stick / slip), normal part >= 0
///   deformable: patch of surface nodes under the fingertip (fem::ContactPatchFinder::Sphere;
///               a beating body: the proxy runs on the rest surface, the fingertip moved back
///               by the mode's displacement s M near it),
///               all fingers of all hands on the object in one fem::ContactSolver::Solve,
///               f_E = -(sum of the patch's node forces on the object)
/// then the sum over objects is clamped to max_force_N, and every dynamic body receives minus
/// exactly what its fingertips feel (equal and opposite), plus gravity and support, and is
/// integrated (semi-implicit Euler).

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "handshare/contact/finger_contact.hpp"
#include "handshare/contact/mesh_collider.hpp"
#include "handshare/contact/proxy.hpp"
#include "handshare/contact/tri_mesh.hpp"
#include "handshare/common/hand.hpp"
#include "handshare/fem/compliance.hpp"
#include "handshare/fem/contact_patch.hpp"
#include "handshare/fem/contact_solver.hpp"
#include "handshare/fem/mesh.hpp"
#include "handshare/fem/stiffening.hpp"

namespace handshare::contact {

/// Fingers per hand (thumb, index, middle, ring, little): the one count of handshare/common/hand.hpp.
using common::kFingers;

/// Gravity magnitudes of the scenes [m/s^2] (use as Eigen::Vector3d(0, 0, -kMoonGravity...)).
inline constexpr double kEarthGravity_m_per_s2 = 9.81;
inline constexpr double kMoonGravity_m_per_s2 = 1.62;
inline constexpr double kMarsGravity_m_per_s2 = 3.71;

/// Contact material of a rigid object (per object).
struct RigidMaterial {
  double stiffness_N_per_m = 1000.0;  ///< k: force per metre of penetration.
  double damping_N_s_per_m = 2.0;     ///< b: along the normal, on the penetration rate.
  double mu_static = 0.6;             ///< Coulomb, proxy sticks while |f_t| <= mu_s f_n.
  double mu_kinetic = 0.5;            ///< Coulomb, sliding proxy keeps |f_t| = mu_k f_n.
};

/// Shape of a rigid object in its frame O (spheres and boxes centred at O). Spheres and boxes
/// are meshed once at setup (icosphere, 12-triangle box) so one proxy algorithm serves all.
struct Shape {
  enum class Kind : std::uint8_t { kSphere, kBox, kMesh };
  Kind kind = Kind::kSphere;
  double radius_m = 0.03;
  Eigen::Vector3d size_m = Eigen::Vector3d::Constant(0.1);  ///< box full edge lengths.
  std::shared_ptr<const TriMesh> mesh;                      ///< kMesh, in O.
  int sphere_subdivisions = 4;                              ///< 20 * 4^s triangles.

  static Shape Sphere(double radius_m, int subdivisions = 4);
  static Shape Box(const Eigen::Vector3d& size_m);
  static Shape Mesh(std::shared_ptr<const TriMesh> mesh);
};

/// Mass properties of a dynamic body; its frame B is at the centre of mass.
struct BodyProperties {
  double mass_kg = 0.1;
  /// Inertia about the centre of mass in B [kg m^2]; zero: uniform solid of the shape (sphere,
  /// box; a mesh uses its bounding box).
  Eigen::Matrix3d inertia_B_kg_m2 = Eigen::Matrix3d::Zero();
  Eigen::Vector3d v_WB_m_per_s = Eigen::Vector3d::Zero();
  Eigen::Vector3d w_WB_rad_per_s = Eigen::Vector3d::Zero();
  double linear_damping_N_s_per_m = 0.0;    ///< air-like drag -c v (settling), 0 = none.
  double angular_damping_N_m_s = 0.0;       ///< -c w.
};

/// A ground or table: the half-space n . p < offset is solid; it pushes dynamic bodies out
/// (spring-damper per support point, regularized Coulomb friction).
struct SupportPlane {
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitZ();
  double offset_m = 0.0;
  double stiffness_N_per_m = 5000.0;
  double damping_N_s_per_m = 10.0;
  double mu = 0.5;
  double slip_velocity_m_per_s = 1e-3;  ///< friction ramps in below this sliding speed.
};

/// A deformable object: linear FEM with a precomputed compliance (handshare::fem).
struct DeformableDesc {
  std::shared_ptr<const fem::TetMesh> mesh;         ///< reference configuration, frame O.
  std::shared_ptr<const fem::Compliance> compliance;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  std::int32_t max_patch_nodes = 16;  ///< per fingertip (closest kept); the solve is O(m^3).
  double regularization_m_per_N = 0.0;  ///< fem::ContactSolverOptions (0 = exact).
  /// Coulomb friction of a fingertip on the surface (fem::FrictionPatch): a fingertip patch
  /// sticks to the material it pressed while |F_t| <= mu_static F_n and drags it along, and
  /// slips with |F_t| = mu_kinetic F_n. Both 0: frictionless (the normal-only solve).
  double mu_static = 0.0;
  double mu_kinetic = 0.0;
  /// A beating body (scene::Beat, world::PreparedDeformable::mode_O_m): the displacement of
  /// every node of `mesh` (frame O) at mode scale 1; the surface is at rest + s mode, s set by
  /// SetModeScale. The compliance must hold the nodes that drive it (linear elasticity: a
  /// fingertip's field adds to s mode). Null: no mode.
  std::shared_ptr<const std::vector<Eigen::Vector3d>> mode_O_m;
  /// The large-deformation correction (fem::StiffeningTable; docs/fem.md, "A correction beyond
  /// the paper"): each fingertip patch's force, a hand's and a peer's, scaled by its nodes' gains
  /// weighted by their push. Null: the linear model's force.
  std::shared_ptr<const fem::StiffeningTable> stiffening;
};

struct WorldConfig {
  /// Hands that may touch one deformable together (this one + remote); sizes the solvers.
  std::int32_t max_hands = 2;
  double fingertip_radius_m = 0.008;  ///< DeviceCapabilities::fingertip_radius_m.
  double max_force_N = 3.5;           ///< per finger clamp (DeviceCapabilities).
  Eigen::Vector3d gravity_W_m_per_s2 = Eigen::Vector3d(0, 0, -kEarthGravity_m_per_s2);
  ProxyParams proxy{};                ///< radius_m is set from fingertip_radius_m.
  std::int32_t max_candidates = 512;  ///< triangles per collision query.
};

/// What one local finger feels and touches this step: in W what the device and this node's
/// display use (force felt, proxy, the main contact), and in `contact` what the hand shares
/// with the others (FingerContact, frame O). Plain data.
///
/// The main contact is one state: `contact` (frame O) is where it is made, and p_WC_m, n_W,
/// u_W_m, depth_m, object and main_node are that contact seen in W at the object's pose of
/// this step (HapticWorld derives them from it, in one place). Both are kept because their
/// readers differ: the device, the controls and the display work in W and need no object pose
/// to read them; the peers, the server and the bridge need the contact in O. The force is the
/// other way round: f_E_W_N (on the fingertip, clamped) is what the device gets, and
/// contact.f_O_N is minus it in O.
struct FingerResult {
  /// The main contact (largest force) as the hand shares it: frame O, force on the object
  /// (finger_contact.hpp). contact.object -1: this finger touches nothing.
  FingerContact contact;
  Eigen::Vector3d f_E_W_N = Eigen::Vector3d::Zero();  ///< force on the fingertip, clamped.
  Eigen::Vector3d p_WP_m = Eigen::Vector3d::Zero();   ///< proxy (IHIP) centre; fingertip if free.
  Eigen::Vector3d e_PE_W_m = Eigen::Vector3d::Zero(); ///< penetration vector, proxy -> fingertip.
  Eigen::Vector3d p_WC_m = Eigen::Vector3d::Zero();   ///< X_WO contact.p_OC_m: contact point (a
                                                      ///< deformable's: undeformed, at rest; with
                                                      ///< friction, where this step's patch was
                                                      ///< found plus its slide, so that a peer
                                                      ///< rebuilds that patch: p_WC - stick).
  Eigen::Vector3d n_W = Eigen::Vector3d::Zero();      ///< R_WO contact.n_O: outward unit normal.
  Eigen::Vector3d u_W_m = Eigen::Vector3d::Zero();    ///< R_WO contact.u_O_m: a deformable's imposed
                                                      ///< displacement (the indentation -depth n_W
                                                      ///< plus the stick).
  double depth_m = 0.0;                 ///< contact.depth_m: penetration along n.
  ObjectId object = -1;                 ///< contact.object: main object (largest force), -1 if none.
  std::int32_t main_node = -1;          ///< contact.node: a deformable's patch node nearest the
                                        ///< contact point.
  std::int32_t patch_nodes = 0;         ///< deformable: nodes in the patch.
  std::int32_t objects_touched = 0;
  bool valid = false;                   ///< input finite (else zero force).
  bool in_contact = false;
  bool sticking = false;                ///< inside the static friction cone.
  bool clamped = false;                 ///< force norm limited to max_force_N.
  bool truncated = false;               ///< a buffer overflowed (candidates or patch nodes).
};

/// Summary of one Step().
struct StepReport {
  bool ok = true;                 ///< false: bad dt or input size: every force is zero.
  std::int32_t invalid_fingers = 0;
  std::int32_t solver_faults = 0; ///< deformable solves that failed (their forces zeroed).
  std::int32_t remote_rejected = 0;
};

/// What a scene's objects are, for haptic rendering: const once built (HapticWorld::Init), so
/// any number of worlds on any threads may read it at once. Built only through a HapticWorld's
/// setup calls; each object's parts are private to the contact sources.
class HapticModel {
 public:
  struct Object;  ///< one object's collider, material, mass, compliance (world_object.hpp)
  ~HapticModel();
  HapticModel(const HapticModel&) = delete;
  HapticModel& operator=(const HapticModel&) = delete;

  const WorldConfig& config() const noexcept { return config_; }
  std::int32_t num_objects() const noexcept { return static_cast<std::int32_t>(objects_.size()); }
  bool has_support() const noexcept { return has_support_; }
  const SupportPlane& support() const noexcept { return support_; }
  const Object& object(std::size_t k) const noexcept { return *objects_[k]; }

 private:
  friend class HapticWorld;
  explicit HapticModel(const WorldConfig& config);
  WorldConfig config_;
  bool has_support_ = false;
  SupportPlane support_{};
  std::vector<std::unique_ptr<Object>> objects_;
};

class HapticWorld {
 public:
  explicit HapticWorld(const WorldConfig& config = {});
  /// A world of its own (poses, velocities, proxies, solver states as the model starts them)
  /// on a model another world built and Init()ed: already initialized, ready to Step.
  /// @throws std::invalid_argument for a null model.
  explicit HapticWorld(std::shared_ptr<const HapticModel> model);
  ~HapticWorld();
  HapticWorld(const HapticWorld&) = delete;
  HapticWorld& operator=(const HapticWorld&) = delete;

  // ---- Setup (allocates; throws std::invalid_argument or fem::FemError on bad input) ----
  /// A fixed rigid object at pose X_WO.
  ObjectId AddStatic(const Shape& shape, const RigidMaterial& material, const Eigen::Isometry3d& X_WO);
  /// A dynamic rigid body with its centre of mass at X_WB.
  ObjectId AddDynamic(const Shape& shape, const RigidMaterial& material, const BodyProperties& body,
                      const Eigen::Isometry3d& X_WB);
  /// A deformable; the proxy runs on its undeformed surface.
  ObjectId AddDeformable(const DeformableDesc& desc);
  /// Ground/table for the dynamic bodies (none by default).
  void SetSupport(const SupportPlane& plane);
  void SetGravity(const Eigen::Vector3d& g_W_m_per_s2);
  /// Sizes every per-step buffer. Objects cannot be added afterwards.
  void Init();

  // ---- Real time (noexcept, no allocation) ----
  /// One haptic step.
  /// @param dt_s    step [s] (> 0): damping velocities and body integration.
  /// @param p_WE_m  the local hand's fingertip centres in W [m], thumb first: 0 to kFingers of
  ///                them (a device with fewer contact points passes fewer; fingers beyond touch
  ///                nothing; the world server, which has no hand, passes none). Non-finite
  ///                entries give that finger zero force and flag it invalid (its proxies are kept).
  /// @param remote  other hands' contacts on shared objects, faded as the caller wants them
  ///                (FadedContact): deformables: one solve with them; dynamic bodies: their
  ///                forces push the body.
  StepReport Step(double dt_s, std::span<const Eigen::Vector3d> p_WE_m,
                  std::span<const FingerContact> remote = {}) noexcept;

  std::span<const FingerResult> fingers() const noexcept;
  /// Deformable: the held nodes' loads of the last solve (forces on the object, frame O), for
  /// the deformation the world server publishes. Empty for other objects.
  std::span<const fem::NodeLoad> held_loads(ObjectId id) const noexcept;
  /// The last step's force of each remote contact's patch on its deformable [N], in the
  /// object's frame O (the frame of the contact's u_O_m), by the contact's index in Step's
  /// `remote` span (zero: not a deformable's, rejected, or beyond kMaxRemoteForces): what the
  /// coupling's passivity observer reads (coupling_passivity.hpp).
  std::span<const Eigen::Vector3d> remote_forces_O() const noexcept {
    return {remote_force_O_.data(), num_remote_forces_};
  }
  static constexpr std::size_t kMaxRemoteForces = 64;
  /// Deformable: its solver (last solve's per-input forces and states), or nullptr.
  const fem::ContactSolver* contact_solver(ObjectId id) const noexcept;
  /// Pose of an object (dynamic bodies: current).
  Eigen::Isometry3d pose(ObjectId id) const noexcept;
  Eigen::Vector3d body_velocity_W(ObjectId id) const noexcept;
  /// Moves an object (static: teleport; dynamic: also zeroes its velocity). Its proxies move
  /// with it. Real-time safe.
  void SetPose(ObjectId id, const Eigen::Isometry3d& X_WO) noexcept;
  /// Deformable with a mode: the surface is at rest + s mode from the next step on (a
  /// fingertip presses the moved surface; its patch and force are the contact's part, which
  /// adds to s mode). Ignored for other objects and non-finite s. Real-time safe.
  void SetModeScale(ObjectId id, double s) noexcept;
  double mode_scale(ObjectId id) const noexcept;
  /// Sets a dynamic body's linear and angular velocity (call after SetPose, which zeroes them):
  /// a body handed over from another simulation keeps its motion. Ignored for other objects
  /// and for non-finite values. Real-time safe.
  void SetVelocity(ObjectId id, const Eigen::Vector3d& v_W_m_per_s, const Eigen::Vector3d& w_W_rad_per_s) noexcept;
  /// Sum of the last step's reactions of the local fingertips on the object [N] (minus what
  /// the fingertips feel).
  Eigen::Vector3d finger_reaction_W(ObjectId id) const noexcept;
  std::int32_t num_objects() const noexcept { return model_->num_objects(); }
  /// Where finger `finger`'s proxy on `object` is, in W, touching or not (a free proxy sits on
  /// its fingertip); false (p untouched) for a bad index or a proxy that has not started.
  bool proxy_W(int finger, ObjectId object, Eigen::Vector3d& p_WP_m) const noexcept;
  const WorldConfig& config() const noexcept { return model_->config(); }
  /// The model this world steps (complete once Init() returned).
  const HapticModel& model() const noexcept { return *model_; }
  /// The model to build more worlds on (HapticWorld(std::shared_ptr<const HapticModel>));
  /// null before Init().
  std::shared_ptr<const HapticModel> shared_model() const noexcept { return initialized_ ? model_ : nullptr; }

 private:
  using Object = HapticModel::Object;
  struct ObjectData;
  struct PatchMemo;
  struct FingerObject;
  struct HandData;
  /// A deformable's inputs as its stage gathers them: nodes so far, friction patches so far.
  struct PatchGather {
    std::int32_t m = 0;
    std::int16_t num_friction = 0;
  };
  /// The model while it is built; throws std::logic_error after Init().
  HapticModel& Setup(const char* what);
  /// The data of model object m as a world starts it (setup; allocates).
  ObjectData MakeObjectData(const Object& m) const;
  /// Sizes the per-step buffers and the hand's data (setup; allocates).
  void SizeBuffers();

  // ---- The stages of Step, each in the file that says so ----
  /// haptic_world.cpp: clears the last step's results; false (report not ok) for a bad dt or
  /// more than kFingers fingertips.
  bool BeginStep(double dt_s, std::span<const Eigen::Vector3d> p_WE, std::span<const FingerContact> remote,
                 StepReport& report) noexcept;
  /// finger_stages.cpp: fingertip i at p_WE against every object (ProxyStep each).
  void CollideFinger(int i, const Eigen::Vector3d& p_WE, double dt_s, StepReport& report) noexcept;
  /// finger_stages.cpp: finger i's proxy on object k (a fingertip not `valid` keeps its proxy
  /// and touches nothing), and a rigid object's spring-damper force.
  void ProxyStep(int i, std::size_t k, bool valid, const Eigen::Vector3d& p_WE, double dt_s) noexcept;
  /// finger_stages.cpp: finger i's forces summed and clamped, and its main contact (MainContact).
  void ResolveFinger(int i, const Eigen::Vector3d& p_WE) noexcept;
  /// Finger i's main contact, on object k: its proxy and Coulomb state, the contact it shares
  /// (SharedContact) and that contact seen in W.
  void MainContact(int i, std::size_t k, const Eigen::Vector3d& p_WE, FingerResult& res) const noexcept;
  /// Finger i's contact on object k as the hand shares it (FingerResult::contact), frame O, from
  /// its fingertip centre p_WE, the patch node nearest the contact and the force it feels f_E_W.
  FingerContact SharedContact(int i, std::size_t k, const Eigen::Vector3d& p_WE, std::int32_t main_node,
                              const Eigen::Vector3d& f_E_W) const noexcept;
  /// deformable_stage.cpp: every hand's patches on deformable k (model m, data d) in one solve.
  void StepDeformable(const Object& m, ObjectData& d, std::size_t k, std::span<const FingerContact> remote,
                      StepReport& report) noexcept;
  void GatherLocalPatch(const Object& m, ObjectData& d, std::size_t k, int i, PatchGather& g) noexcept;
  void GatherRemotePatch(const Object& m, ObjectData& d, std::size_t k, std::size_t r, const FingerContact& rc,
                         PatchGather& g, StepReport& report) noexcept;
  void AddPatch(const Object& m, ObjectData& d, PatchGather& g, const Eigen::Vector3d& p_O, const Eigen::Vector3d& n_O,
                double depth, std::int32_t& count, bool& truncated, PatchMemo* memo = nullptr,
                fem::ContactInput* kept = nullptr) noexcept;
  void ApplyFingerPatch(const Object& m, ObjectData& d, FingerObject& fo, std::span<const Eigen::Vector3d> forces) noexcept;
  // The stiffening gain of the patch of `count` inputs from `begin` (1 without a table).
  double PatchGain(const Object& m, const ObjectData& d, std::int32_t begin, std::int32_t count,
                   std::span<const Eigen::Vector3d> forces, const Eigen::Vector3d& n_O,
                   const Eigen::Vector3d& stick_O) const noexcept;
  /// A moded deformable: s mode at the surface point nearest g_O (interpolated over its
  /// triangle), zero if no surface is within reach of the fingertip.
  Eigen::Vector3d ModeShift(const Object& m, const ObjectData& d, const Eigen::Vector3d& g_O) noexcept;
  /// body_stage.cpp: the fingertips' reactions and the other hands' forces on the bodies.
  void ApplyReactions(std::span<const FingerContact> remote, StepReport& report) noexcept;
  /// body_stage.cpp: every dynamic body over dt_s (StepBody).
  void IntegrateBodies(double dt_s) noexcept;
  /// A dynamic body over dt_s, in substeps of at most kMaxBodySubstep_s (the forces the
  /// fingers put on it held): a stalled loop hands in a long dt_s, and one explicit step of
  /// the support spring (5000 N/m under a 0.2 kg ball: stable below about 12 ms) over it
  /// throws the body. dt_s is capped at kMaxBodyStep_s (the body then lags the wall clock).
  void StepBody(const Object& m, ObjectData& d, double dt_s) noexcept;
  void SubstepBody(const Object& m, ObjectData& d, double h_s) noexcept;
  static constexpr double kMaxBodySubstep_s = 2e-3;
  static constexpr double kMaxBodyStep_s = 0.1;

  // The model: const from Init() on; setup_ is the same object while it is built.
  std::shared_ptr<const HapticModel> model_;
  HapticModel* setup_ = nullptr;
  bool initialized_ = false;
  // The data, world_object.hpp: each object's in this world (by object index), the hand's.
  std::vector<ObjectData> data_;
  std::unique_ptr<HandData> hand_;
  // Per-step scratch.
  ProxySolver proxy_solver_;
  std::vector<std::int32_t> mode_candidates_;  // ModeShift's ball query
  std::array<Eigen::Vector3d, kMaxRemoteForces> remote_force_O_{};
  std::size_t num_remote_forces_ = 0;
  // Each remote contact's patch in its deformable's inputs (begin, count), this step.
  std::array<std::pair<std::int32_t, std::int32_t>, kMaxRemoteForces> remote_patch_{};
  // Each remote patch's normal and stick (frame O), for the stiffening gain of its force.
  std::array<Eigen::Vector3d, kMaxRemoteForces> remote_n_O_{};
  std::array<Eigen::Vector3d, kMaxRemoteForces> remote_stick_O_{};
};

}  // namespace handshare::contact
