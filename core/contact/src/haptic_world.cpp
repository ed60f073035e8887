#include "handshare/contact/haptic_world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "handshare/contact/geometry.hpp"
#include "handshare/fem/error.hpp"
#include "world_object.hpp"

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

HapticModel::HapticModel(const WorldConfig& config) : config_(config) {
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

HapticModel::~HapticModel() = default;

HapticWorld::HapticWorld(const WorldConfig& config)
    : hand_(std::make_unique<HandData>()), proxy_solver_(config.max_candidates) {
  std::shared_ptr<HapticModel> model(new HapticModel(config));
  setup_ = model.get();
  model_ = std::move(model);
}

HapticWorld::HapticWorld(std::shared_ptr<const HapticModel> model)
    : model_(std::move(model)),
      hand_(std::make_unique<HandData>()),
      proxy_solver_(model_ ? model_->config().max_candidates : 1) {
  if (!model_) throw std::invalid_argument("HapticWorld: null model");
  data_.reserve(model_->objects_.size());
  for (const auto& o : model_->objects_) data_.push_back(MakeObjectData(*o));
  SizeBuffers();
  initialized_ = true;
}

HapticWorld::~HapticWorld() = default;

HapticModel& HapticWorld::Setup(const char* what) {
  if (initialized_ || setup_ == nullptr) throw std::logic_error(std::string("HapticWorld::") + what + " after Init()");
  return *setup_;
}

HapticWorld::ObjectData HapticWorld::MakeObjectData(const Object& m) const {
  ObjectData d;
  d.X_WO = m.X_WO0;
  d.v_W = m.v_W0;
  d.w_W = m.w_W0;
  if (m.kind == ObjectKind::kDeformable) {
    d.solver = std::make_unique<fem::ContactSolver>(m.compliance, m.solver_options);
    d.inputs.assign(static_cast<std::size_t>(m.solver_options.max_contacts), fem::ContactInput{});
    d.friction.assign(static_cast<std::size_t>(m.solver_options.max_friction_patches), fem::FrictionPatch{});
    d.remote_memo.assign(kMaxRemoteForces, PatchMemo{});
    d.remote_memo_inputs.assign(kMaxRemoteForces * static_cast<std::size_t>(m.max_patch), fem::ContactInput{});
  }
  return d;
}

void HapticWorld::SizeBuffers() {
  hand_->fo.assign(static_cast<std::size_t>(kFingers) * data_.size(), FingerObject{});
  for (auto& r : hand_->results) r = FingerResult{};
  mode_candidates_.assign(static_cast<std::size_t>(config().max_candidates), 0);
}

ObjectId HapticWorld::AddStatic(const Shape& shape, const RigidMaterial& material,
                                const Eigen::Isometry3d& X_WO) {
  HapticModel& model = Setup("AddStatic");
  CheckMaterial(material);
  if (!FiniteIsometry(X_WO)) throw std::invalid_argument("AddStatic: X_WO is not a finite rigid pose");
  auto o = std::make_unique<Object>();
  o->kind = ObjectKind::kStatic;
  o->collider = std::make_unique<MeshCollider>(MeshOf(shape), config().max_candidates);
  o->material = material;
  o->X_WO0 = X_WO;
  data_.push_back(MakeObjectData(*o));
  model.objects_.push_back(std::move(o));
  return static_cast<ObjectId>(model.objects_.size() - 1);
}

ObjectId HapticWorld::AddDynamic(const Shape& shape, const RigidMaterial& material,
                                 const BodyProperties& body, const Eigen::Isometry3d& X_WB) {
  HapticModel& model = Setup("AddDynamic");
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
  o->collider = std::make_unique<MeshCollider>(mesh, config().max_candidates);
  o->material = material;
  o->X_WO0 = X_WB;
  o->mass_kg = body.mass_kg;
  o->v_W0 = body.v_WB_m_per_s;
  o->w_W0 = body.w_WB_rad_per_s;
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
  data_.push_back(MakeObjectData(*o));
  model.objects_.push_back(std::move(o));
  return static_cast<ObjectId>(model.objects_.size() - 1);
}

ObjectId HapticWorld::AddDeformable(const DeformableDesc& d) {
  HapticModel& model = Setup("AddDeformable");
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
  o->X_WO0 = d.X_WO;
  const fem::Surface surface = fem::ExtractSurface(*d.mesh);
  auto tri = std::make_shared<TriMesh>();
  tri->p_O_m = d.mesh->positions_m();
  tri->triangles.assign(surface.triangles.begin(), surface.triangles.end());
  o->collider = std::make_unique<MeshCollider>(std::move(tri), config().max_candidates);
  o->patches = std::make_unique<fem::ContactPatchFinder>(*d.mesh, surface, *d.compliance);
  o->max_patch = d.max_patch_nodes;
  o->mu_static = d.mu_static;
  o->mu_kinetic = d.mu_kinetic;
  o->stiffening = d.stiffening;
  fem::ContactSolverOptions& so = o->solver_options;
  so.max_contacts = config().max_hands * kFingers * d.max_patch_nodes;
  so.push_only = true;
  so.regularization_m_per_N = d.regularization_m_per_N;
  so.max_friction_patches = config().max_hands * kFingers;
  data_.push_back(MakeObjectData(*o));
  model.objects_.push_back(std::move(o));
  return static_cast<ObjectId>(model.objects_.size() - 1);
}

void HapticWorld::SetSupport(const SupportPlane& plane) {
  HapticModel& model = Setup("SetSupport");
  if (!plane.n_W.allFinite() || !(plane.n_W.norm() > 0.0) || !std::isfinite(plane.offset_m) ||
      !(plane.stiffness_N_per_m > 0.0) || !(plane.damping_N_s_per_m >= 0.0) || !(plane.mu >= 0.0) ||
      !(plane.slip_velocity_m_per_s > 0.0)) {
    throw std::invalid_argument("SetSupport: need a finite nonzero normal, stiffness > 0, damping, mu >= 0");
  }
  model.support_ = plane;
  model.support_.n_W.normalize();
  model.has_support_ = true;
}

void HapticWorld::SetGravity(const Eigen::Vector3d& g) {
  HapticModel& model = Setup("SetGravity");
  if (!g.allFinite()) throw std::invalid_argument("SetGravity: not finite");
  model.config_.gravity_W_m_per_s2 = g;
}

void HapticWorld::Init() {
  Setup("Init");
  SizeBuffers();
  setup_ = nullptr;  // the model is const from here on
  initialized_ = true;
}

std::span<const FingerResult> HapticWorld::fingers() const noexcept {
  return {hand_->results.data(), hand_->results.size()};
}

std::span<const fem::NodeLoad> HapticWorld::held_loads(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects() || !data_[static_cast<std::size_t>(id)].solver) return {};
  return data_[static_cast<std::size_t>(id)].solver->loads();
}

const fem::ContactSolver* HapticWorld::contact_solver(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return nullptr;
  return data_[static_cast<std::size_t>(id)].solver.get();
}

Eigen::Isometry3d HapticWorld::pose(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return Eigen::Isometry3d::Identity();
  return data_[static_cast<std::size_t>(id)].X_WO;
}

Eigen::Vector3d HapticWorld::body_velocity_W(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return Eigen::Vector3d::Zero();
  return data_[static_cast<std::size_t>(id)].v_W;
}

Eigen::Vector3d HapticWorld::finger_reaction_W(ObjectId id) const noexcept {
  if (id < 0 || id >= num_objects()) return Eigen::Vector3d::Zero();
  return data_[static_cast<std::size_t>(id)].reaction_W_N;
}

bool HapticWorld::proxy_W(int finger, ObjectId object, Eigen::Vector3d& p_WP_m) const noexcept {
  if (!initialized_ || finger < 0 || finger >= kFingers || object < 0 || object >= num_objects()) return false;
  const FingerObject& fo = hand_->at(finger, static_cast<std::size_t>(object), data_.size());
  if (!fo.proxy.initialized) return false;
  p_WP_m = data_[static_cast<std::size_t>(object)].X_WO * (fo.proxy.x_O_m + fo.shift_O_m);
  return true;
}

void HapticWorld::SetModeScale(ObjectId id, double s) noexcept {
  if (id < 0 || id >= num_objects() || !std::isfinite(s)) return;
  if (model_->object(static_cast<std::size_t>(id)).mode) data_[static_cast<std::size_t>(id)].mode_scale = s;
}

double HapticWorld::mode_scale(ObjectId id) const noexcept {
  return id >= 0 && id < num_objects() ? data_[static_cast<std::size_t>(id)].mode_scale : 0.0;
}


void HapticWorld::SetPose(ObjectId id, const Eigen::Isometry3d& X) noexcept {
  if (id < 0 || id >= num_objects() || !X.matrix().allFinite()) return;
  ObjectData& d = data_[static_cast<std::size_t>(id)];
  d.X_WO = X;
  d.v_W.setZero();
  d.w_W.setZero();
}

void HapticWorld::SetVelocity(ObjectId id, const Eigen::Vector3d& v_W, const Eigen::Vector3d& w_W) noexcept {
  if (id < 0 || id >= num_objects() || !v_W.allFinite() || !w_W.allFinite()) return;
  if (model_->object(static_cast<std::size_t>(id)).kind != ObjectKind::kDynamic) return;
  ObjectData& d = data_[static_cast<std::size_t>(id)];
  d.v_W = v_W;
  d.w_W = w_W;
}


Eigen::Vector3d HapticWorld::ModeShift(const Object& o, const ObjectData& d, const Eigen::Vector3d& g) noexcept {
  const double s = d.mode_scale;
  const double reach = config().fingertip_radius_m + std::abs(s) * o.mode_reach_m + 1e-3;
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

StepReport HapticWorld::Step(double dt_s, std::span<const Eigen::Vector3d> p_WE,
                             std::span<const FingerContact> remote) noexcept {
  StepReport report;
  if (!BeginStep(dt_s, p_WE, remote, report)) return report;
  // 1. Each fingertip against every object: collision, proxy, rigid force. A finger the hand
  //    does not have (p_WE shorter than kFingers) touches nothing.
  const std::size_t num_obj = data_.size();
  for (int i = 0; i < kFingers; ++i) {
    const auto f = static_cast<std::size_t>(i);
    if (f < p_WE.size()) {
      CollideFinger(i, p_WE[f], dt_s, report);
    } else {
      for (std::size_t k = 0; k < num_obj; ++k) ProxyStep(i, k, false, Eigen::Vector3d::Zero(), dt_s);
    }
  }
  // 2. Each deformable: every hand's patches on it (local and remote, one path) in one solve.
  for (std::size_t k = 0; k < num_obj; ++k) {
    const Object& m = model_->object(k);
    if (m.kind == ObjectKind::kDeformable) StepDeformable(m, data_[k], k, remote, report);
  }
  // 3. Each finger: its forces summed and clamped, its main contact (what it shares).
  for (std::size_t f = 0; f < p_WE.size(); ++f) ResolveFinger(static_cast<int>(f), p_WE[f]);
  // 4. Dynamic bodies: minus what the fingertips feel, the other hands' forces; they move.
  ApplyReactions(remote, report);
  IntegrateBodies(dt_s);
  return report;
}

bool HapticWorld::BeginStep(double dt_s, std::span<const Eigen::Vector3d> p_WE, std::span<const FingerContact> remote,
                            StepReport& report) noexcept {
  auto& results = hand_->results;
  for (auto& r : results) r = FingerResult{};
  for (std::size_t i = 0; i < results.size(); ++i) results[i].contact.finger = static_cast<std::int32_t>(i);
  hand_->scale.fill(0.0);
  if (!initialized_ || !(dt_s > 0.0) || !std::isfinite(dt_s) || p_WE.size() > static_cast<std::size_t>(kFingers)) {
    report.ok = false;
    report.invalid_fingers = kFingers;
    return false;
  }
  for (auto& d : data_) d.reaction_W_N.setZero();
  num_remote_forces_ = std::min(remote.size(), kMaxRemoteForces);
  for (std::size_t r = 0; r < num_remote_forces_; ++r) remote_force_O_[r].setZero();
  return true;
}

}  // namespace handshare::contact
