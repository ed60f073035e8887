#include "handshare/contact/haptic_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "handshare/contact/geometry.hpp"
#include "handshare/fem/error.hpp"

namespace handshare::contact {

Shape Shape::Sphere(double radius_m, int subdivisions) {
  Shape s;
  s.kind = Kind::kSphere;
  s.radius_m = radius_m;
  s.sphere_subdivisions = subdivisions;
  return s;
}
Shape Shape::Box(const Eigen::Vector3d& size_m) {
  Shape s;
  s.kind = Kind::kBox;
  s.size_m = size_m;
  return s;
}
Shape Shape::Mesh(std::shared_ptr<const TriMesh> mesh) {
  Shape s;
  s.kind = Kind::kMesh;
  s.mesh = std::move(mesh);
  return s;
}

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
  // Each remote contact's patch as last found (by its index in the remote list): its query bit
  // for bit and the nodes it gave. A peer's contact set changes at the network's rate, not the
  // haptic loop's, so most steps ask the same query again and copy the answer.
  struct PatchMemo {
    Eigen::Vector3d p_O_m = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    Eigen::Vector3d n_O = Eigen::Vector3d::Zero();
    double depth_m = 0.0;
    std::int32_t room = -1;
    std::int32_t count = 0;
    bool truncated = false;
  };
  std::vector<PatchMemo> remote_memo;
  std::vector<fem::ContactInput> remote_memo_inputs;  // max_patch per memo
  std::shared_ptr<const std::vector<Eigen::Vector3d>> mode;  // per node, frame O; null: none
  double mode_reach_m = 0.0;  // largest |mode|
  double mode_scale = 0.0;
};

namespace {

std::shared_ptr<const TriMesh> MeshOf(const Shape& s) {
  switch (s.kind) {
    case Shape::Kind::kSphere:
      return std::make_shared<const TriMesh>(MakeIcosphere(s.radius_m, s.sphere_subdivisions));
    case Shape::Kind::kBox:
      return std::make_shared<const TriMesh>(MakeBoxMesh(s.size_m));
    case Shape::Kind::kMesh:
      if (!s.mesh) throw std::invalid_argument("Shape::Mesh: null mesh");
      return s.mesh;
  }
  throw std::invalid_argument("Shape: unknown kind");
}

bool FiniteIsometry(const Eigen::Isometry3d& X) {
  return X.matrix().allFinite() &&
         (X.linear() * X.linear().transpose() - Eigen::Matrix3d::Identity()).norm() < 1e-6;
}

void CheckMaterial(const RigidMaterial& m) {
  if (!(m.stiffness_N_per_m > 0.0) || !std::isfinite(m.stiffness_N_per_m) ||
      !(m.damping_N_s_per_m >= 0.0) || !std::isfinite(m.damping_N_s_per_m) ||
      !(m.mu_static >= 0.0) || !(m.mu_kinetic >= 0.0) || !(m.mu_kinetic <= m.mu_static) ||
      !std::isfinite(m.mu_static)) {
    throw std::invalid_argument(
        "RigidMaterial: need stiffness_N_per_m > 0, damping_N_s_per_m >= 0, "
        "0 <= mu_kinetic <= mu_static, all finite");
  }
}

}  // namespace

HapticWorld::HapticWorld(const WorldConfig& config)
    : config_(config), proxy_solver_(config.max_candidates) {
  if (config_.max_hands < 1 || config_.max_hands > 16) {
    throw std::invalid_argument("WorldConfig.max_hands must be in 1..16");
  }
  if (!(config_.fingertip_radius_m > 0.0) || !(config_.max_force_N > 0.0) ||
      !config_.gravity_W_m_per_s2.allFinite() || config_.max_candidates < 1) {
    throw std::invalid_argument(
        "WorldConfig: fingertip_radius_m and max_force_N must be > 0, gravity finite, "
        "max_candidates >= 1");
  }
  config_.proxy.radius_m = config_.fingertip_radius_m;
}

HapticWorld::~HapticWorld() = default;

void HapticWorld::CheckSetup(const char* what) const {
  if (initialized_) throw std::logic_error(std::string("HapticWorld::") + what + " after Init()");
}

ObjectId HapticWorld::AddStatic(const Shape& shape, const RigidMaterial& material,
                                const Eigen::Isometry3d& X_WO) {
  CheckSetup("AddStatic");
  CheckMaterial(material);
  if (!FiniteIsometry(X_WO)) throw std::invalid_argument("AddStatic: X_WO is not a finite rigid pose");
  auto o = std::make_unique<Object>();
  o->kind = ObjectKind::kStatic;
  o->collider = std::make_unique<MeshCollider>(MeshOf(shape), config_.max_candidates);
  o->material = material;
  o->X_WO = X_WO;
  objects_.push_back(std::move(o));
  return static_cast<ObjectId>(objects_.size() - 1);
}

ObjectId HapticWorld::AddDynamic(const Shape& shape, const RigidMaterial& material,
                                 const BodyProperties& body, const Eigen::Isometry3d& X_WB) {
  CheckSetup("AddDynamic");
  CheckMaterial(material);
  if (!FiniteIsometry(X_WB)) throw std::invalid_argument("AddDynamic: X_WB is not a finite rigid pose");
  if (!(body.mass_kg > 0.0) || !std::isfinite(body.mass_kg) || !body.inertia_B_kg_m2.allFinite() ||
      !body.v_WB_m_per_s.allFinite() || !body.w_WB_rad_per_s.allFinite() ||
      !(body.linear_damping_N_s_per_m >= 0.0) || !(body.angular_damping_N_m_s >= 0.0)) {
    throw std::invalid_argument("AddDynamic: mass must be > 0, inertia and velocities finite, damping >= 0");
  }
  auto o = std::make_unique<Object>();
  o->kind = ObjectKind::kDynamic;
  auto mesh = MeshOf(shape);
  o->collider = std::make_unique<MeshCollider>(mesh, config_.max_candidates);
  o->material = material;
  o->X_WO = X_WB;
  o->mass_kg = body.mass_kg;
  o->v_W = body.v_WB_m_per_s;
  o->w_W = body.w_WB_rad_per_s;
  o->lin_damp = body.linear_damping_N_s_per_m;
  o->ang_damp = body.angular_damping_N_m_s;
  Eigen::Matrix3d I = body.inertia_B_kg_m2;
  if (I.isZero(0.0)) {
    const double m = body.mass_kg;
    if (shape.kind == Shape::Kind::kSphere) {
      I = Eigen::Matrix3d::Identity() * (0.4 * m * shape.radius_m * shape.radius_m);
    } else {
      Eigen::Vector3d s = shape.size_m;
      if (shape.kind == Shape::Kind::kMesh) {
        Eigen::Vector3d lo = mesh->p_O_m[0], hi = lo;
        for (const auto& p : mesh->p_O_m) {
          lo = lo.cwiseMin(p);
          hi = hi.cwiseMax(p);
        }
        s = hi - lo;
      }
      I = (m / 12.0) * Eigen::Vector3d(s.y() * s.y() + s.z() * s.z(), s.x() * s.x() + s.z() * s.z(),
                                       s.x() * s.x() + s.y() * s.y()).asDiagonal();
    }
  }
  Eigen::LLT<Eigen::Matrix3d> llt(I);
  if (llt.info() != Eigen::Success) throw std::invalid_argument("AddDynamic: inertia is not positive definite");
  o->I_B = I;
  o->I_B_inv = I.inverse();
  if (shape.kind == Shape::Kind::kSphere) {
    o->round = true;
    o->radius_m = shape.radius_m;
  } else {
    o->support_points_B = mesh->p_O_m;  // box: its 8 corners; mesh: every vertex
  }
  objects_.push_back(std::move(o));
  return static_cast<ObjectId>(objects_.size() - 1);
}

ObjectId HapticWorld::AddDeformable(const DeformableDesc& d) {
  CheckSetup("AddDeformable");
  if (!d.mesh || !d.compliance) throw std::invalid_argument("AddDeformable: null mesh or compliance");
  if (!FiniteIsometry(d.X_WO)) throw std::invalid_argument("AddDeformable: X_WO is not a finite rigid pose");
  if (d.max_patch_nodes < 1) throw std::invalid_argument("AddDeformable: max_patch_nodes must be >= 1");
  if (!(d.mu_static >= 0.0) || !(d.mu_kinetic >= 0.0) || !(d.mu_kinetic <= d.mu_static) ||
      !std::isfinite(d.mu_static)) {
    throw std::invalid_argument("AddDeformable: need 0 <= mu_kinetic <= mu_static, all finite");
  }
  if (d.mode_O_m) {
    if (static_cast<std::int32_t>(d.mode_O_m->size()) != d.mesh->num_nodes()) {
      throw std::invalid_argument("AddDeformable: the mode has " + std::to_string(d.mode_O_m->size()) +
                                  " displacements for " + std::to_string(d.mesh->num_nodes()) + " nodes");
    }
    for (const auto& m : *d.mode_O_m) {
      if (!m.allFinite()) throw std::invalid_argument("AddDeformable: the mode has a non-finite displacement");
    }
  }
  auto o = std::make_unique<Object>();
  o->kind = ObjectKind::kDeformable;
  o->mode = d.mode_O_m;
  if (o->mode) {
    for (const auto& m : *o->mode) o->mode_reach_m = std::max(o->mode_reach_m, m.norm());
  }
  o->tet = d.mesh;
  o->compliance = d.compliance;
  o->X_WO = d.X_WO;
  const fem::Surface surface = fem::ExtractSurface(*d.mesh);
  auto tri = std::make_shared<TriMesh>();
  tri->p_O_m = d.mesh->positions_m();
  tri->triangles.assign(surface.triangles.begin(), surface.triangles.end());
  o->collider = std::make_unique<MeshCollider>(std::move(tri), config_.max_candidates);
  o->patches = std::make_unique<fem::ContactPatchFinder>(*d.mesh, surface, *d.compliance);
  o->max_patch = d.max_patch_nodes;
  o->mu_static = d.mu_static;
  o->mu_kinetic = d.mu_kinetic;
  const std::int32_t max_contacts = config_.max_hands * kFingers * d.max_patch_nodes;
  fem::ContactSolverOptions so;
  so.max_contacts = max_contacts;
  so.push_only = true;
  so.regularization_m_per_N = d.regularization_m_per_N;
  so.max_friction_patches = config_.max_hands * kFingers;
  o->solver = std::make_unique<fem::ContactSolver>(d.compliance, so);
  o->inputs.assign(static_cast<std::size_t>(max_contacts), fem::ContactInput{});
  o->friction.assign(static_cast<std::size_t>(so.max_friction_patches), fem::FrictionPatch{});
  o->remote_memo.assign(kMaxRemoteForces, Object::PatchMemo{});
  o->remote_memo_inputs.assign(kMaxRemoteForces * static_cast<std::size_t>(d.max_patch_nodes), fem::ContactInput{});
  objects_.push_back(std::move(o));
  return static_cast<ObjectId>(objects_.size() - 1);
}

void HapticWorld::SetSupport(const SupportPlane& plane) {
  CheckSetup("SetSupport");
  if (!plane.n_W.allFinite() || !(plane.n_W.norm() > 0.0) || !std::isfinite(plane.offset_m) ||
      !(plane.stiffness_N_per_m > 0.0) || !(plane.damping_N_s_per_m >= 0.0) || !(plane.mu >= 0.0) ||
      !(plane.slip_velocity_m_per_s > 0.0)) {
    throw std::invalid_argument("SetSupport: need a finite nonzero normal, stiffness > 0, damping, mu >= 0");
  }
  support_ = plane;
  support_.n_W.normalize();
  has_support_ = true;
}

void HapticWorld::SetGravity(const Eigen::Vector3d& g) {
  CheckSetup("SetGravity");
  if (!g.allFinite()) throw std::invalid_argument("SetGravity: not finite");
  config_.gravity_W_m_per_s2 = g;
}

void HapticWorld::Init() {
  CheckSetup("Init");
  fo_.assign(static_cast<std::size_t>(kFingers) * objects_.size(), FingerObject{});
  for (auto& r : results_) r = FingerResult{};
  mode_candidates_.assign(static_cast<std::size_t>(config_.max_candidates), 0);
  initialized_ = true;
}

std::span<const fem::NodeLoad> HapticWorld::held_loads(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects() || !objects_[static_cast<std::size_t>(id)]->solver) return {};
  return objects_[static_cast<std::size_t>(id)]->solver->loads();
}

const fem::ContactSolver* HapticWorld::contact_solver(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return nullptr;
  return objects_[static_cast<std::size_t>(id)]->solver.get();
}

Eigen::Isometry3d HapticWorld::pose(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return Eigen::Isometry3d::Identity();
  return objects_[static_cast<std::size_t>(id)]->X_WO;
}

Eigen::Vector3d HapticWorld::body_velocity_W(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return Eigen::Vector3d::Zero();
  return objects_[static_cast<std::size_t>(id)]->v_W;
}

Eigen::Vector3d HapticWorld::finger_reaction_W(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return Eigen::Vector3d::Zero();
  return objects_[static_cast<std::size_t>(id)]->reaction_W_N;
}

bool HapticWorld::proxy_W(int finger, ObjectId object, Eigen::Vector3d& p_WP_m) const noexcept {
  if (!initialized_ || finger < 0 || finger >= kFingers || object < 0 || object >= num_objects()) return false;
  const FingerObject& fo = fo_[static_cast<std::size_t>(finger) * objects_.size() + static_cast<std::size_t>(object)];
  if (!fo.proxy.initialized) return false;
  p_WP_m = objects_[static_cast<std::size_t>(object)]->X_WO * (fo.proxy.x_O_m + fo.shift_O_m);
  return true;
}

void HapticWorld::SetModeScale(ObjectId id, double s) noexcept {
  if (id < 0 || id >= num_objects() || !std::isfinite(s)) return;
  Object& o = *objects_[static_cast<std::size_t>(id)];
  if (o.mode) o.mode_scale = s;
}

double HapticWorld::mode_scale(ObjectId id) const noexcept {
  return id >= 0 && id < num_objects() ? objects_[static_cast<std::size_t>(id)]->mode_scale : 0.0;
}

Eigen::Vector3d HapticWorld::ModeShift(const Object& o, const Eigen::Vector3d& g) noexcept {
  const double s = o.mode_scale;
  const double reach = config_.fingertip_radius_m + std::abs(s) * o.mode_reach_m + 1e-3;
  const BallQueryResult q = o.collider->QueryBall(g, reach, mode_candidates_);
  if (q.count == 0) return Eigen::Vector3d::Zero();
  const TriMesh& mesh = o.collider->mesh();
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d shift = Eigen::Vector3d::Zero();
  for (std::int32_t c = 0; c < q.count; ++c) {
    const auto& t = mesh.triangles[static_cast<std::size_t>(mode_candidates_[static_cast<std::size_t>(c)])];
    const Eigen::Vector3d& a = mesh.p_O_m[static_cast<std::size_t>(t[0])];
    const Eigen::Vector3d& b = mesh.p_O_m[static_cast<std::size_t>(t[1])];
    const Eigen::Vector3d& cc = mesh.p_O_m[static_cast<std::size_t>(t[2])];
    const Eigen::Vector3d x = ClosestPointOnTriangle(g, a, b, cc);
    const double d2 = (x - g).squaredNorm();
    if (d2 >= best) continue;
    best = d2;
    // Barycentric weights of x (on the triangle): the mode is linear over it.
    const Eigen::Vector3d n = (b - a).cross(cc - a);
    const double area2 = n.squaredNorm();
    double wa = 1.0 / 3.0, wb = 1.0 / 3.0, wc = 1.0 / 3.0;
    if (area2 > 0.0) {
      wa = (b - x).cross(cc - x).dot(n) / area2;
      wb = (cc - x).cross(a - x).dot(n) / area2;
      wc = 1.0 - wa - wb;
    }
    const auto& M = *o.mode;
    shift = s * (wa * M[static_cast<std::size_t>(t[0])] + wb * M[static_cast<std::size_t>(t[1])] +
                 wc * M[static_cast<std::size_t>(t[2])]);
  }
  return shift;
}

void HapticWorld::SetPose(ObjectId id, const Eigen::Isometry3d& X) noexcept {
  if (id < 0 || id >= num_objects() || !X.matrix().allFinite()) return;
  Object& o = *objects_[static_cast<std::size_t>(id)];
  o.X_WO = X;
  o.v_W.setZero();
  o.w_W.setZero();
}

void HapticWorld::SetVelocity(ObjectId id, const Eigen::Vector3d& v_W, const Eigen::Vector3d& w_W) noexcept {
  if (id < 0 || id >= num_objects() || !v_W.allFinite() || !w_W.allFinite()) return;
  Object& o = *objects_[static_cast<std::size_t>(id)];
  if (o.kind != ObjectKind::kDynamic) return;
  o.v_W = v_W;
  o.w_W = w_W;
}

StepReport HapticWorld::Step(double dt_s, std::span<const Eigen::Vector3d> p_WE,
                             std::span<const FingerContact> remote) noexcept {
  StepReport report;
  const auto num_obj = static_cast<std::size_t>(objects_.size());
  for (auto& r : results_) r = FingerResult{};
  if (!initialized_ || !(dt_s > 0.0) || !std::isfinite(dt_s) || p_WE.size() != static_cast<std::size_t>(kFingers)) {
    report.ok = false;
    report.invalid_fingers = kFingers;
    return report;
  }
  for (auto& o : objects_) o->reaction_W_N.setZero();
  num_remote_forces_ = std::min(remote.size(), kMaxRemoteForces);
  for (std::size_t r = 0; r < num_remote_forces_; ++r) remote_force_O_[r].setZero();

  // Stage 1: proxies of every valid finger on every object; rigid contact forces.
  for (int i = 0; i < kFingers; ++i) {
    FingerResult& res = results_[static_cast<std::size_t>(i)];
    const Eigen::Vector3d& p = p_WE[static_cast<std::size_t>(i)];
    res.valid = p.allFinite() && p.cwiseAbs().maxCoeff() < 1e3;
    res.p_WP_m = res.valid ? p : Eigen::Vector3d::Zero();
    if (!res.valid) ++report.invalid_fingers;
    for (std::size_t k = 0; k < num_obj; ++k) {
      Object& o = *objects_[k];
      FingerObject& fo = fo_[static_cast<std::size_t>(i) * num_obj + k];
      fo.contact = ProxyContact{};
      fo.f_W_N.setZero();
      fo.patch_count = 0;
      if (!res.valid) {
        fo.prev_valid = false;  // proxies are kept: the next valid sample continues from them
        continue;
      }
      const bool deformable = o.kind == ObjectKind::kDeformable;
      Eigen::Vector3d g_O = o.X_WO.inverse() * p;
      fo.shift_O_m.setZero();
      if (deformable && o.mode && o.mode_scale != 0.0) {
        fo.shift_O_m = ModeShift(o, g_O);
        g_O -= fo.shift_O_m;
      }
      FrictionParams fr;
      if (!deformable) fr = {o.material.mu_static, o.material.mu_kinetic};
      fo.contact = proxy_solver_.Step(*o.collider, config_.proxy, fr, g_O, fo.proxy);
      const Eigen::Vector3d v_O = fo.prev_valid ? Eigen::Vector3d((g_O - fo.prev_goal_O_m) / dt_s)
                                                : Eigen::Vector3d::Zero();
      fo.prev_goal_O_m = g_O;
      fo.prev_valid = true;
      if (!fo.contact.touching || deformable) continue;
      // Rigid: spring from fingertip to proxy, damping on the normal approach speed; the
      // surface only pushes (a negative normal part would be glue: no force then).
      const Eigen::Vector3d& n = fo.contact.n_O;
      // The proxy rests skin_m off the surface: measure the spring from the surface itself.
      Eigen::Vector3d f_O =
          o.material.stiffness_N_per_m * (fo.contact.x_O_m - g_O - config_.proxy.skin_m * n);
      f_O -= o.material.damping_N_s_per_m * v_O.dot(n) * n;
      if (f_O.dot(n) <= 0.0) f_O.setZero();
      fo.f_W_N = o.X_WO.linear() * f_O;
    }
  }

  // Stage 2: deformables, every finger of every hand on the object in one solve.
  for (auto& op : objects_) {
    if (op->kind == ObjectKind::kDeformable) StepDeformable(*op, remote, report);
  }

  // Stage 3: per finger: sum, clamp, the main contact for the result.
  for (int i = 0; i < kFingers; ++i) {
    FingerResult& res = results_[static_cast<std::size_t>(i)];
    scale_[static_cast<std::size_t>(i)] = 0.0;
    if (!res.valid) continue;
    Eigen::Vector3d f = Eigen::Vector3d::Zero();
    double best = -1.0;
    for (std::size_t k = 0; k < num_obj; ++k) {
      const FingerObject& fo = fo_[static_cast<std::size_t>(i) * num_obj + k];
      res.truncated = res.truncated || fo.contact.truncated;
      if (!fo.contact.touching) continue;
      ++res.objects_touched;
      f += fo.f_W_N;
      const double mag = fo.f_W_N.norm();
      if (mag <= best) continue;
      best = mag;
      const Object& o = *objects_[k];
      res.object = static_cast<ObjectId>(k);
      res.p_WP_m = o.X_WO * (fo.contact.x_O_m + fo.shift_O_m);
      res.e_PE_W_m = p_WE[static_cast<std::size_t>(i)] - res.p_WP_m;
      res.p_WC_m = o.X_WO * fo.contact.p_O_m;
      res.n_W = o.X_WO.linear() * fo.contact.n_O;
      res.depth_m = fo.contact.depth_m;
      res.sticking = fo.contact.sticking;
      res.in_contact = true;
      res.main_node = -1;
      res.patch_nodes = 0;
      res.u_W_m.setZero();
      if (o.kind == ObjectKind::kDeformable) {
        res.sticking = fo.friction_patch >= 0 && !fo.slipped;  // the patch's Coulomb state
        res.u_W_m = -fo.contact.depth_m * res.n_W;
        if (fo.friction_patch >= 0) {
          res.u_W_m += o.X_WO.linear() * fo.solved_slide_O_m;  // and its stick
          // The contact point a peer rebuilds this step's patch from: its center, slid. A patch
          // that slipped was found at the anchor it had before the slip; from the proxy's point
          // (the anchor after it) a peer's patch took other nodes and solved another force:
          // on the beating belly, 0.74 N where the user felt 0.89 N (docs/fem.md).
          res.p_WC_m = o.X_WO * (fo.patch_center_O_m + fo.solved_slide_O_m);
        }
        res.patch_nodes = fo.patch_count;
        double best_d = std::numeric_limits<double>::infinity();
        const auto& P = o.tet->positions_m();
        for (std::int32_t q = 0; q < fo.patch_count; ++q) {
          const std::int32_t node = o.inputs[static_cast<std::size_t>(fo.patch_begin + q)].node;
          const double dq = (P[static_cast<std::size_t>(node)] - fo.contact.p_O_m).squaredNorm();
          if (dq < best_d) {
            best_d = dq;
            res.main_node = node;
          }
        }
      }
    }
    const double norm = f.norm();
    double s = 1.0;
    if (norm > config_.max_force_N) {
      s = config_.max_force_N / norm;
      res.clamped = true;
    }
    scale_[static_cast<std::size_t>(i)] = s;
    res.f_E_W_N = s * f;
    res.contact = SharedContact(i, res, p_WE[static_cast<std::size_t>(i)]);
  }

  // Stage 4: dynamic bodies get minus what the fingertips feel (after the clamp), remote hands'
  // reported forces, gravity and support; then they move.
  for (std::size_t k = 0; k < num_obj; ++k) {
    Object& o = *objects_[k];
    for (int i = 0; i < kFingers; ++i) {
      const FingerObject& fo = fo_[static_cast<std::size_t>(i) * num_obj + k];
      if (!fo.contact.touching) continue;
      const Eigen::Vector3d r = -scale_[static_cast<std::size_t>(i)] * fo.f_W_N;
      o.reaction_W_N += r;
      if (o.kind == ObjectKind::kDynamic) {
        o.force_W += r;
        o.torque_W += (o.X_WO * fo.contact.p_O_m - o.X_WO.translation()).cross(r);
      }
    }
  }
  for (const FingerContact& rc : remote) {
    if (rc.object < 0 || rc.object >= num_objects()) {
      ++report.remote_rejected;
      continue;
    }
    Object& o = *objects_[static_cast<std::size_t>(rc.object)];
    if (o.kind != ObjectKind::kDynamic) continue;
    if (!AsVector(rc.f_O_N).allFinite() || !AsVector(rc.p_OC_m).allFinite()) {
      ++report.remote_rejected;
      continue;
    }
    const Eigen::Vector3d f_W = o.X_WO.linear() * AsVector(rc.f_O_N);  // on the body
    o.force_W += f_W;
    o.torque_W += (o.X_WO.linear() * AsVector(rc.p_OC_m)).cross(f_W);
  }
  for (auto& op : objects_) {
    if (op->kind == ObjectKind::kDynamic) StepBody(*op, dt_s);
  }
  return report;
}

FingerContact HapticWorld::SharedContact(int i, const FingerResult& res, const Eigen::Vector3d& p_WE) const noexcept {
  FingerContact c;
  c.finger = i;
  if (!res.valid || !res.in_contact || res.object < 0) return c;
  const Object& o = *objects_[static_cast<std::size_t>(res.object)];
  const FingerObject& fo = fo_[static_cast<std::size_t>(i) * objects_.size() + static_cast<std::size_t>(res.object)];
  const Eigen::Matrix3d R_OW = o.X_WO.linear().transpose();
  c.object = res.object;
  c.node = res.main_node;
  c.depth_m = res.depth_m;
  c.n_O = ToVec3(fo.contact.n_O);
  c.p_OE_m = ToVec3(R_OW * (p_WE - o.X_WO.translation()));
  c.f_O_N = ToVec3(R_OW * -res.f_E_W_N);  // on the object: minus what the fingertip feels
  Eigen::Vector3d p_OC = fo.contact.p_O_m;
  if (o.kind == ObjectKind::kDeformable) {
    Eigen::Vector3d u_O = -fo.contact.depth_m * fo.contact.n_O;
    if (fo.friction_patch >= 0) {
      u_O += fo.solved_slide_O_m;                      // and its stick
      p_OC = fo.patch_center_O_m + fo.solved_slide_O_m;  // where a peer rebuilds this patch (FingerResult::p_WC_m)
    }
    c.u_O_m = ToVec3(u_O);
  }
  c.p_OC_m = ToVec3(p_OC);
  return c;
}

void HapticWorld::StepDeformable(Object& o, std::span<const FingerContact> remote,
                                 StepReport& report) noexcept {
  const auto num_obj = static_cast<std::size_t>(objects_.size());
  std::size_t k = 0;
  while (objects_[k].get() != &o) ++k;
  const double R = config_.fingertip_radius_m;
  const auto cap = static_cast<std::int32_t>(o.inputs.size());
  std::int32_t m = 0;
  // With a memo (a remote contact's), the patch is copied from it while its query is bit for bit
  // the same, and found and kept in it otherwise.
  auto add_patch = [&](const Eigen::Vector3d& p_O, const Eigen::Vector3d& n_O, double depth,
                       std::int32_t& count, bool& truncated, Object::PatchMemo* memo = nullptr,
                       fem::ContactInput* kept = nullptr) {
    count = 0;
    const std::int32_t room = std::min(o.max_patch, cap - m);
    if (room <= 0 || !(depth > 0.0)) return;
    if (memo != nullptr && memo->room == room && memo->depth_m == depth && memo->p_O_m == p_O && memo->n_O == n_O) {
      std::copy(kept, kept + memo->count, o.inputs.begin() + m);
      count = memo->count;
      truncated = memo->truncated;
      m += count;
      return;
    }
    const fem::PatchResult pr =
        o.patches->Sphere(p_O, n_O, R, depth, fem::ContactMode::kNormalOnly,
                          std::span<fem::ContactInput>(o.inputs.data() + m, static_cast<std::size_t>(room)));
    count = pr.count;
    truncated = pr.truncated;
    if (memo != nullptr) {
      std::copy(o.inputs.begin() + m, o.inputs.begin() + m + count, kept);
      *memo = Object::PatchMemo{p_O, n_O, depth, room, count, truncated};
    }
    m += pr.count;
  };
  // Local fingers: the patch under each proxy, pressed to the proxy's depth. With friction the
  // fingertip holds the material point it first pressed (its anchor): the patch is centred there
  // and slides with the fingertip by the tangential offset (the stick) while the cone holds it;
  // the solve says where it slipped to, and the anchor follows.
  const bool friction = o.mu_static > 0.0;  // mu_kinetic <= mu_static
  std::int16_t num_friction = 0;
  for (int i = 0; i < kFingers; ++i) {
    FingerObject& fo = fo_[static_cast<std::size_t>(i) * num_obj + k];
    fo.patch_begin = m;
    fo.patch_count = 0;
    fo.friction_patch = -1;
    if (!fo.contact.touching) {
      fo.anchored = false;
      fo.slipped = false;
      continue;
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
      const Eigen::Vector3d d = p - fo.anchor_O_m;
      stick = d - d.dot(n) * n;
    }
    bool trunc = false;
    fo.patch_center_O_m = p - stick;
    add_patch(fo.patch_center_O_m, n, fo.contact.depth_m, fo.patch_count, trunc);
    if (friction && fo.patch_count == 0 && stick.squaredNorm() > 0.0) {
      // No node under the anchor (a slide left it off the fingertip's footprint): without a
      // patch the anchor would never move again and the fingertip would feel nothing while it
      // presses. It holds the material under it now instead.
      anchor_here();
      stick.setZero();
      fo.patch_center_O_m = p;
      add_patch(p, n, fo.contact.depth_m, fo.patch_count, trunc);
    }
    fo.contact.truncated = fo.contact.truncated || trunc;
    if (!friction || fo.patch_count == 0) continue;
    for (std::int32_t q = 0; q < fo.patch_count; ++q) o.inputs[static_cast<std::size_t>(fo.patch_begin + q)].patch = num_friction;
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
      const Eigen::Vector3d d = fo.slip_dir_O - fo.slip_dir_O.dot(n) * n;
      if (speed > 0.0 && d.squaredNorm() > 0.0) {  // a unit vector plus 2 % of one: never short
        fo.slip_dir_O = (d.normalized() + kSlipTurn * (m_t / speed)).normalized();
        motion = speed * fo.slip_dir_O;
      }
    }
    o.friction[static_cast<std::size_t>(num_friction)] = {n, stick, o.mu_static, o.mu_kinetic, fo.slipped,
                                                          motion, /*peer=*/false};
    fo.friction_patch = num_friction++;
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
  std::array<std::pair<std::int32_t, std::int32_t>, kMaxRemoteForces> remote_patch{};
  for (std::size_t r = 0; r < remote.size(); ++r) {
    const FingerContact& rc = remote[r];
    if (rc.object < 0 || rc.object >= num_objects() || objects_[static_cast<std::size_t>(rc.object)].get() != &o) continue;
    const auto p_OC = AsVector(rc.p_OC_m), u_O = AsVector(rc.u_O_m), n_in = AsVector(rc.n_O);
    if (!p_OC.allFinite() || !u_O.allFinite() || !n_in.allFinite() || !(u_O.norm() > 0.0)) {
      ++report.remote_rejected;
      continue;
    }
    const double nn = n_in.norm();
    const Eigen::Vector3d n_O = (nn > 0.5 && nn < 2.0) ? Eigen::Vector3d(n_in / nn) : Eigen::Vector3d(-u_O / u_O.norm());
    const double depth = -u_O.dot(n_O);
    if (!(depth > 0.0)) {
      ++report.remote_rejected;  // pulls the surface out: not a press
      continue;
    }
    const Eigen::Vector3d stick_O = u_O + depth * n_O;
    const bool sticks = stick_O.norm() > 1e-12 && num_friction < static_cast<std::int16_t>(o.friction.size());
    std::int32_t count = 0;
    bool trunc = false;
    const std::int32_t begin = m;
    const bool memo = r < kMaxRemoteForces;
    add_patch(p_OC - (sticks ? stick_O : Eigen::Vector3d::Zero()), n_O, depth, count, trunc,
              memo ? &o.remote_memo[r] : nullptr,
              memo ? o.remote_memo_inputs.data() + r * static_cast<std::size_t>(o.max_patch) : nullptr);
    if (r < kMaxRemoteForces) remote_patch[r] = {begin, count};
    if (!sticks || count == 0) continue;
    for (std::int32_t q = 0; q < count; ++q) o.inputs[static_cast<std::size_t>(begin + q)].patch = num_friction;
    o.friction[static_cast<std::size_t>(num_friction++)] = {n_O, stick_O, o.mu_static, o.mu_kinetic, false,
                                                            Eigen::Vector3d::Zero(), /*peer=*/true};
  }
  o.num_inputs = m;
  const fem::StepStatus st = o.solver->Solve(
      std::span<const fem::ContactInput>(o.inputs.data(), static_cast<std::size_t>(m)),
      std::span<const fem::FrictionPatch>(o.friction.data(), static_cast<std::size_t>(num_friction)));
  const bool failed = st == fem::StepStatus::kInvalidInput || st == fem::StepStatus::kNumericalFailure;
  if (failed) ++report.solver_faults;
  const auto forces = o.solver->forces_N();
  for (std::size_t r = 0; r < num_remote_forces_ && !failed; ++r) {
    const auto [begin, count] = remote_patch[r];
    if (count == 0) continue;
    Eigen::Vector3d f_obj = Eigen::Vector3d::Zero();
    for (std::int32_t q = 0; q < count; ++q) f_obj += forces[static_cast<std::size_t>(begin + q)];
    remote_force_O_[r] = f_obj;
  }
  for (int i = 0; i < kFingers; ++i) {
    FingerObject& fo = fo_[static_cast<std::size_t>(i) * num_obj + k];
    if (!fo.contact.touching || failed) continue;
    Eigen::Vector3d f_obj = Eigen::Vector3d::Zero();
    for (std::int32_t q = 0; q < fo.patch_count; ++q) f_obj += forces[static_cast<std::size_t>(fo.patch_begin + q)];
    fo.f_W_N = -(o.X_WO.linear() * f_obj);  // the fingertip feels minus the force on the object
    if (fo.friction_patch >= 0) {
      const fem::FrictionPatchState& ps = o.solver->patch_states()[static_cast<std::size_t>(fo.friction_patch)];
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
}

void HapticWorld::StepBody(Object& o, double dt) noexcept {
  dt = std::min(dt, kMaxBodyStep_s);
  const int n = std::max(1, static_cast<int>(std::ceil(dt / kMaxBodySubstep_s - 1e-9)));
  for (int k = 0; k < n; ++k) SubstepBody(o, dt / n);
  o.force_W.setZero();
  o.torque_W.setZero();
}

void HapticWorld::SubstepBody(Object& o, double dt) noexcept {
  Eigen::Vector3d F = o.force_W + o.mass_kg * config_.gravity_W_m_per_s2 - o.lin_damp * o.v_W;
  Eigen::Vector3d T = o.torque_W - o.ang_damp * o.w_W;
  const Eigen::Vector3d c = o.X_WO.translation();
  if (has_support_) {
    const SupportPlane& s = support_;
    auto push = [&](const Eigen::Vector3d& p) {
      const double pen = s.offset_m - s.n_W.dot(p);
      if (!(pen > 0.0)) return;
      const Eigen::Vector3d v = o.v_W + o.w_W.cross(p - c);
      const double vn = v.dot(s.n_W);
      const double fn = std::max(0.0, s.stiffness_N_per_m * pen - s.damping_N_s_per_m * vn);
      const Eigen::Vector3d vt = v - vn * s.n_W;
      const double vt_norm = vt.norm();
      // Regularized Coulomb: full mu f_n above the slip speed, proportional below it.
      const Eigen::Vector3d ft = -s.mu * fn * vt / std::max(vt_norm, s.slip_velocity_m_per_s);
      const Eigen::Vector3d f = fn * s.n_W + ft;
      F += f;
      T += (p - c).cross(f);
    };
    if (o.round) {
      push(c - o.radius_m * s.n_W);
    } else {
      for (const auto& pb : o.support_points_B) push(o.X_WO * pb);
    }
  }
  // Semi-implicit (symplectic) Euler: velocities first, then poses with the new velocities.
  const Eigen::Matrix3d Rm = o.X_WO.linear();
  const Eigen::Matrix3d I_W = Rm * o.I_B * Rm.transpose();
  const Eigen::Matrix3d I_W_inv = Rm * o.I_B_inv * Rm.transpose();
  o.v_W += dt * F / o.mass_kg;
  o.w_W += dt * (I_W_inv * (T - o.w_W.cross(I_W * o.w_W)));
  if (!o.v_W.allFinite() || !o.w_W.allFinite()) {
    o.v_W.setZero();
    o.w_W.setZero();
  }
  o.X_WO.translation() += dt * o.v_W;
  const double angle = o.w_W.norm() * dt;
  if (angle > 0.0) {
    Eigen::Quaterniond q(Eigen::AngleAxisd(angle, o.w_W.normalized()) * Eigen::Quaterniond(Rm));
    q.normalize();
    o.X_WO.linear() = q.toRotationMatrix();
  }
}

}  // namespace handshare::contact
