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
  const auto num_obj = objects_.size();
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
}

void HapticWorld::IntegrateBodies(double dt_s) noexcept {
  for (auto& op : objects_) {
    if (op->kind == ObjectKind::kDynamic) StepBody(*op, dt_s);
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
