// The haptic world's per-finger stages: a fingertip against every object (collision, proxy,
// rigid force), then its forces summed and clamped, with the main contact it shares.
#include <cmath>
#include <limits>

#include "handshare/contact/haptic_world.hpp"
#include "world_object.hpp"

namespace handshare::contact {

void HapticWorld::CollideFinger(int i, const Eigen::Vector3d& p, double dt_s, StepReport& report) noexcept {
  FingerResult& res = hand_->results[static_cast<std::size_t>(i)];
  res.valid = p.allFinite() && p.cwiseAbs().maxCoeff() < 1e3;
  res.p_WP_m = res.valid ? p : Eigen::Vector3d::Zero();
  if (!res.valid) ++report.invalid_fingers;
  for (std::size_t k = 0; k < data_.size(); ++k) ProxyStep(i, k, res.valid, p, dt_s);
}

void HapticWorld::ProxyStep(int i, std::size_t k, bool valid, const Eigen::Vector3d& p, double dt_s) noexcept {
  const Object& o = model_->object(k);
  const ObjectData& d = data_[k];
  FingerObject& fo = hand_->at(i, k, data_.size());
  fo.contact = ProxyContact{};
  fo.f_W_N.setZero();
  fo.patch_count = 0;
  if (!valid) {
    fo.prev_valid = false;  // proxies are kept: the next valid sample continues from them
    return;
  }
  const bool deformable = o.kind == ObjectKind::kDeformable;
  Eigen::Vector3d g_O = d.X_WO.inverse() * p;
  fo.shift_O_m.setZero();
  if (deformable && o.mode && d.mode_scale != 0.0) {
    fo.shift_O_m = ModeShift(o, d, g_O);
    g_O -= fo.shift_O_m;
  }
  FrictionParams fr;
  if (!deformable) fr = {o.material.mu_static, o.material.mu_kinetic};
  fo.contact = proxy_solver_.Step(*o.collider, config().proxy, fr, g_O, fo.proxy);
  const Eigen::Vector3d v_O = fo.prev_valid ? Eigen::Vector3d((g_O - fo.prev_goal_O_m) / dt_s)
                                            : Eigen::Vector3d::Zero();
  fo.prev_goal_O_m = g_O;
  fo.prev_valid = true;
  if (!fo.contact.touching || deformable) return;
  // Rigid: spring from fingertip to proxy, damping on the normal approach speed; the
  // surface only pushes (a negative normal part would be glue: no force then).
  const Eigen::Vector3d& n = fo.contact.n_O;
  // The proxy rests skin_m off the surface: measure the spring from the surface itself.
  Eigen::Vector3d f_O =
      o.material.stiffness_N_per_m * (fo.contact.x_O_m - g_O - config().proxy.skin_m * n);
  f_O -= o.material.damping_N_s_per_m * v_O.dot(n) * n;
  if (f_O.dot(n) <= 0.0) f_O.setZero();
  fo.f_W_N = d.X_WO.linear() * f_O;
}

void HapticWorld::ResolveFinger(int i, const Eigen::Vector3d& p_WE) noexcept {
  const auto num_obj = data_.size();
  FingerResult& res = hand_->results[static_cast<std::size_t>(i)];
  hand_->scale[static_cast<std::size_t>(i)] = 0.0;
  if (!res.valid) return;
  Eigen::Vector3d f = Eigen::Vector3d::Zero();
  double best = -1.0;
  std::size_t main = num_obj;  // the object of the largest force
  for (std::size_t k = 0; k < num_obj; ++k) {
    const FingerObject& fo = hand_->at(i, k, num_obj);
    res.truncated = res.truncated || fo.contact.truncated;
    if (!fo.contact.touching) continue;
    ++res.objects_touched;
    f += fo.f_W_N;
    const double mag = fo.f_W_N.norm();
    if (mag <= best) continue;
    best = mag;
    main = k;
  }
  const double norm = f.norm();
  double s = 1.0;
  if (norm > config().max_force_N) {
    s = config().max_force_N / norm;
    res.clamped = true;
  }
  hand_->scale[static_cast<std::size_t>(i)] = s;
  res.f_E_W_N = s * f;
  if (main < num_obj) MainContact(i, main, p_WE, res);
}

void HapticWorld::MainContact(int i, std::size_t k, const Eigen::Vector3d& p_WE, FingerResult& res) const noexcept {
  const Object& o = model_->object(k);
  const ObjectData& d = data_[k];
  const FingerObject& fo = hand_->at(i, k, data_.size());
  const bool deformable = o.kind == ObjectKind::kDeformable;
  res.in_contact = true;
  res.p_WP_m = d.X_WO * (fo.contact.x_O_m + fo.shift_O_m);
  res.e_PE_W_m = p_WE - res.p_WP_m;
  // A deformable's: the patch's Coulomb state.
  res.sticking = deformable ? fo.friction_patch >= 0 && !fo.slipped : fo.contact.sticking;
  res.patch_nodes = deformable ? fo.patch_count : 0;
  std::int32_t main_node = -1;
  if (deformable) {
    double best_d = std::numeric_limits<double>::infinity();
    const auto& P = o.tet->positions_m();
    for (std::int32_t q = 0; q < fo.patch_count; ++q) {
      const std::int32_t node = d.inputs[static_cast<std::size_t>(fo.patch_begin + q)].node;
      const double dq = (P[static_cast<std::size_t>(node)] - fo.contact.p_O_m).squaredNorm();
      if (dq < best_d) {
        best_d = dq;
        main_node = node;
      }
    }
  }
  res.contact = SharedContact(i, k, p_WE, main_node, res.f_E_W_N);
  // The main contact in W, for the device and this node's display: the shared one seen in W,
  // derived here and nowhere else.
  const FingerContact& c = res.contact;
  res.object = c.object;
  res.main_node = c.node;
  res.depth_m = c.depth_m;
  res.p_WC_m = d.X_WO * AsVector(c.p_OC_m);
  res.n_W = d.X_WO.linear() * AsVector(c.n_O);
  res.u_W_m = deformable ? Eigen::Vector3d(d.X_WO.linear() * AsVector(c.u_O_m)) : Eigen::Vector3d::Zero();
}

FingerContact HapticWorld::SharedContact(int i, std::size_t k, const Eigen::Vector3d& p_WE, std::int32_t main_node,
                                         const Eigen::Vector3d& f_E_W) const noexcept {
  const Object& o = model_->object(k);
  const ObjectData& d = data_[k];
  const FingerObject& fo = hand_->at(i, k, data_.size());
  const Eigen::Matrix3d R_OW = d.X_WO.linear().transpose();
  FingerContact c;
  c.finger = i;
  c.object = static_cast<ObjectId>(k);
  c.node = main_node;
  c.depth_m = fo.contact.depth_m;
  c.n_O = ToVec3(fo.contact.n_O);
  c.p_OE_m = ToVec3(R_OW * (p_WE - d.X_WO.translation()));
  c.f_O_N = ToVec3(R_OW * -f_E_W);  // on the object: minus what the fingertip feels
  Eigen::Vector3d p_OC = fo.contact.p_O_m;
  if (o.kind == ObjectKind::kDeformable) {
    Eigen::Vector3d u_O = -fo.contact.depth_m * fo.contact.n_O;
    if (fo.friction_patch >= 0) {
      u_O += fo.solved_slide_O_m;  // and its stick
      // The contact point a peer rebuilds this step's patch from: its center, slid. A patch
      // that slipped was found at the anchor it had before the slip; from the proxy's point
      // (the anchor after it) a peer's patch took other nodes and solved another force:
      // on the beating belly, 0.74 N where the user felt 0.89 N (docs/fem.md).
      p_OC = fo.patch_center_O_m + fo.solved_slide_O_m;
    }
    c.u_O_m = ToVec3(u_O);
  }
  c.p_OC_m = ToVec3(p_OC);
  return c;
}

}  // namespace handshare::contact
