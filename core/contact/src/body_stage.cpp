// The haptic world's body stage: every dynamic body gets minus what the fingertips feel (after
// the clamp) and the other hands' forces, gravity and its support, and moves.
#include <algorithm>
#include <cmath>

#include "handshare/contact/haptic_world.hpp"
#include "world_object.hpp"

namespace handshare::contact {

// Dynamic bodies get minus what the fingertips feel (after the clamp), remote hands'
// reported forces, gravity and support; then they move.
void HapticWorld::ApplyReactions(std::span<const FingerContact> remote, StepReport& report) noexcept {
  const auto num_obj = data_.size();
  for (std::size_t k = 0; k < num_obj; ++k) {
    const bool dynamic = model_->object(k).kind == ObjectKind::kDynamic;
    ObjectData& d = data_[k];
    for (int i = 0; i < kFingers; ++i) {
      const FingerObject& fo = hand_->at(i, k, num_obj);
      if (!fo.contact.touching) continue;
      const Eigen::Vector3d r = -hand_->scale[static_cast<std::size_t>(i)] * fo.f_W_N;
      d.reaction_W_N += r;
      if (dynamic) {
        d.force_W += r;
        d.torque_W += (d.X_WO * fo.contact.p_O_m - d.X_WO.translation()).cross(r);
      }
    }
  }
  for (const FingerContact& rc : remote) {
    if (rc.object < 0 || rc.object >= num_objects()) {
      ++report.remote_rejected;
      continue;
    }
    const auto k = static_cast<std::size_t>(rc.object);
    if (model_->object(k).kind != ObjectKind::kDynamic) continue;
    ObjectData& d = data_[k];
    if (!AsVector(rc.f_O_N).allFinite() || !AsVector(rc.p_OC_m).allFinite()) {
      ++report.remote_rejected;
      continue;
    }
    const Eigen::Vector3d f_W = d.X_WO.linear() * AsVector(rc.f_O_N);  // on the body
    d.force_W += f_W;
    d.torque_W += (d.X_WO.linear() * AsVector(rc.p_OC_m)).cross(f_W);
  }
}

void HapticWorld::IntegrateBodies(double dt_s) noexcept {
  for (std::size_t k = 0; k < data_.size(); ++k) {
    const Object& m = model_->object(k);
    if (m.kind == ObjectKind::kDynamic) StepBody(m, data_[k], dt_s);
  }
}

void HapticWorld::StepBody(const Object& m, ObjectData& d, double dt) noexcept {
  dt = std::min(dt, kMaxBodyStep_s);
  const int n = std::max(1, static_cast<int>(std::ceil(dt / kMaxBodySubstep_s - 1e-9)));
  for (int k = 0; k < n; ++k) SubstepBody(m, d, dt / n);
  d.force_W.setZero();
  d.torque_W.setZero();
}

// m: what the body is (mass, inertia, damping, support points); d: where it is and how it moves.
void HapticWorld::SubstepBody(const Object& m, ObjectData& d, double dt) noexcept {
  Eigen::Vector3d F = d.force_W + m.mass_kg * config().gravity_W_m_per_s2 - m.lin_damp * d.v_W;
  Eigen::Vector3d T = d.torque_W - m.ang_damp * d.w_W;
  const Eigen::Vector3d c = d.X_WO.translation();
  if (model_->has_support()) {
    const SupportPlane& s = model_->support();
    auto push = [&](const Eigen::Vector3d& p) {
      const double pen = s.offset_m - s.n_W.dot(p);
      if (!(pen > 0.0)) return;
      const Eigen::Vector3d v = d.v_W + d.w_W.cross(p - c);
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
    if (m.round) {
      push(c - m.radius_m * s.n_W);
    } else {
      for (const auto& pb : m.support_points_B) push(d.X_WO * pb);
    }
  }
  // Semi-implicit (symplectic) Euler: velocities first, then poses with the new velocities.
  const Eigen::Matrix3d Rm = d.X_WO.linear();
  const Eigen::Matrix3d I_W = Rm * m.I_B * Rm.transpose();
  const Eigen::Matrix3d I_W_inv = Rm * m.I_B_inv * Rm.transpose();
  d.v_W += dt * F / m.mass_kg;
  d.w_W += dt * (I_W_inv * (T - d.w_W.cross(I_W * d.w_W)));
  if (!d.v_W.allFinite() || !d.w_W.allFinite()) {
    d.v_W.setZero();
    d.w_W.setZero();
  }
  d.X_WO.translation() += dt * d.v_W;
  const double angle = d.w_W.norm() * dt;
  if (angle > 0.0) {
    Eigen::Quaterniond q(Eigen::AngleAxisd(angle, d.w_W.normalized()) * Eigen::Quaterniond(Rm));
    q.normalize();
    d.X_WO.linear() = q.toRotationMatrix();
  }
}

}  // namespace handshare::contact
