#include "bridge_conversions.hpp"

#include <algorithm>
#include <cmath>

#include "handshare/dds/sample_checks.hpp"
#include "handshare/world/grasp.hpp"

namespace handshare::haptic {

namespace {
const std::string& IdOf(const world::SceneModels& models, std::int32_t object) {
  static const std::string kNone;
  return object >= 0 && object < static_cast<std::int32_t>(models.ids.size()) ? models.ids[object] : kNone;
}

bool IsDynamic(const world::SceneModels& models, std::int32_t object) {
  return object >= 0 && std::find(models.dynamic_bodies.begin(), models.dynamic_bodies.end(), object) !=
                            models.dynamic_bodies.end();
}
}  // namespace

void ToDeviceState(const HapticSnapshot& s, msg::DeviceState& out) {
  out.stamp_ns(s.stamp_ns);
  out.seq(static_cast<std::uint32_t>(s.seq));
  for (int k = 0; k < 3; ++k) out.p_WH_m()[k] = s.p_WH_m[k];
  for (int k = 0; k < 4; ++k) out.q_WH_wxyz()[k] = s.q_WH_wxyz[k];
  for (int i = 0; i < kFingers; ++i) {
    for (int k = 0; k < 3; ++k) {
      out.p_WE_m()[i][k] = s.p_WE_m[i][k];
      out.f_E_W_N()[i][k] = s.f_E_W_N[i][k];
    }
  }
  out.fingertip_radius_m(s.fingertip_radius_m);
  for (int j = 0; j < 15; ++j) out.q_hand_rad()[j] = s.q_hand_rad[j];
  for (int j = 0; j < 6; ++j) out.q_arm_rad()[j] = s.q_arm_rad[j];
  out.fault(s.fault);
}

void ToLoopStatistics(const common::LoopStats& s, std::uint64_t faults, msg::LoopStatistics& out) {
  out.rate_Hz(s.rate_Hz);
  out.jitter_p50_us(s.jitter.Quantile(0.5));
  out.jitter_p99_us(s.jitter.Quantile(0.99));
  out.jitter_max_us(s.jitter.max_us());
  out.step_p50_us(s.step.Quantile(0.5));
  out.step_p99_us(s.step.Quantile(0.99));
  out.steps(s.steps);
  out.overruns(s.overruns);
  out.resyncs(s.resyncs);
  out.faults(faults);
}

bool HandGrasps(const ContactReport& r, std::int32_t object) {
  if (object < 0) return false;
  world::FingerForce on_body[kFingers];
  for (int i = 0; i < kFingers; ++i) {
    const auto& f = r.fingers[i];
    on_body[i].active = f.active && f.object == object;
    for (int k = 0; k < 3; ++k) on_body[i].f_W_N[k] = f.f_W_N[k];
  }
  return world::IsGrasp(on_body, kFingers);
}

std::int32_t ClaimedBody(const ContactReport& r) {
  std::int32_t touched = -1;
  double strongest = 0.0;
  for (int b = 0; b < r.num_bodies; ++b) {
    if (HandGrasps(r, r.bodies[b].object)) return r.bodies[b].object;
    for (const auto& f : r.fingers) {
      if (!f.active || f.object != r.bodies[b].object) continue;
      const double norm = std::sqrt(f.f_W_N[0] * f.f_W_N[0] + f.f_W_N[1] * f.f_W_N[1] + f.f_W_N[2] * f.f_W_N[2]);
      if (touched < 0 || norm > strongest) {
        touched = r.bodies[b].object;
        strongest = norm;
      }
    }
  }
  return touched;
}

std::string PeerGrasping(const session::PeerContacts& peers, const std::string& object_id,
                         session::PeerContacts::Clock::time_point now) {
  if (object_id.empty()) return {};
  for (const auto& [user, entry] : peers.sets()) {
    if (peers.Weight(now - entry.received) <= 0.0) continue;
    world::FingerForce on_body[kFingers];
    const auto& fingers = entry.set.fingers();
    for (int i = 0; i < kFingers && i < static_cast<int>(fingers.size()); ++i) {
      on_body[i].active = fingers[i].active() && fingers[i].object_id().to_string() == object_id;
      for (int k = 0; k < 3; ++k) on_body[i].f_W_N[k] = fingers[i].f_W_N()[k];
    }
    if (world::IsGrasp(on_body, kFingers)) return user;
  }
  return {};
}

bool HandOverHold::Update(std::int32_t owned, const ContactReport& report, const std::string& grasper,
                          std::uint64_t now_ns, FollowedBodies& followed) {
  const bool hold = owned >= 0 && !grasper.empty() && !HandGrasps(report, owned);
  if (!hold) {
    object_ = -1;
    return false;
  }
  bool began = false;
  if (object_ != owned) {
    const ContactReport::Body* body = nullptr;
    for (int b = 0; b < report.num_bodies; ++b) {
      if (report.bodies[b].object == owned) body = &report.bodies[b];
    }
    if (body == nullptr) return false;  // not in this world's report: nothing to hold
    object_ = owned;
    at_ = *body;
    ++holds_;
    began = true;
  }
  if (followed.count >= kMaxReportedBodies) return began;
  auto& item = followed.items[followed.count++];
  item.object = object_;
  for (int k = 0; k < 3; ++k) item.p_WO_m[k] = at_.p_WO_m[k];
  for (int k = 0; k < 4; ++k) item.q_WO_wxyz[k] = at_.q_WO_wxyz[k];
  for (int k = 0; k < 3; ++k) item.v_WO_m_per_s[k] = 0.0;
  item.received_ns = now_ns;
  return began;
}

Eigen::Isometry3d PoseOf(const ContactReport::Body& body) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(body.q_WO_wxyz[0], body.q_WO_wxyz[1], body.q_WO_wxyz[2], body.q_WO_wxyz[3])
                   .normalized()
                   .toRotationMatrix();
  X.translation() = Eigen::Vector3d(body.p_WO_m[0], body.p_WO_m[1], body.p_WO_m[2]);
  return X;
}

FollowedBodies ToFollowedBodies(const ReceivedBodies& bodies, const std::string& user,
                                const world::SceneModels& models) {
  FollowedBodies followed;
  for (const auto& [id, received] : bodies) {
    const msg::ObjectState& st = received.state;
    if (st.owner().to_string() == user || followed.count >= kMaxReportedBodies) continue;
    const auto object = models.Find(id);
    if (!IsDynamic(models, object)) continue;
    auto& item = followed.items[followed.count++];
    item.object = object;
    for (int k = 0; k < 3; ++k) item.p_WO_m[k] = st.p_WO_m()[k];
    for (int k = 0; k < 4; ++k) item.q_WO_wxyz[k] = st.q_WO_wxyz()[k];
    for (int k = 0; k < 3; ++k) item.v_WO_m_per_s[k] = st.v_WO_m_per_s()[k];
    item.received_ns = received.received_ns;
  }
  return followed;
}

std::int32_t OwnedBody(const ReceivedBodies& bodies, const std::string& user, const world::SceneModels& models) {
  std::int32_t owned = -1;
  for (const auto& [id, received] : bodies) {
    if (received.state.owner().to_string() == user) owned = models.Find(id);
  }
  return owned;
}

RemoteContacts ToRemoteContacts(const session::PeerContacts& peers, const world::SceneModels& models,
                                session::PeerContacts::Clock::time_point now) {
  RemoteContacts remote;
  remote.fade = peers.fade();
  peers.ForEach(models, now, [&](const contact::PeerContact& c, const msg::ContactSet&) {
    if (remote.count >= kMaxRemoteContacts || models.world->contact_solver(c.object) == nullptr) return;
    remote.items[remote.count++] = c;
  });
  return remote;
}

bool ToContactSet(const ContactReport& report, const world::SceneModels& models, std::int32_t owned,
                  double radius_m, msg::ContactSet& out) {
  // A fingertip far inside an object (pushed through it, or after a stall) reports a depth and
  // an imposed displacement beyond what receivers accept (dds::CheckContactSet): they would
  // drop the whole set, and with it the grasp and the body it carries. Both go out clamped to
  // the accepted size, in their own direction.
  const double max_u_m = dds::SampleBounds{}.max_displacement_m;
  bool active = false;
  for (int i = 0; i < kFingers; ++i) {
    const auto& f = report.fingers[i];
    auto& m = out.fingers()[i];
    m.active(f.active);
    active |= f.active;
    m.object_id(f.active ? IdOf(models, f.object) : std::string());
    m.surface_node(f.node);
    const Eigen::Vector3d u_W_m(f.u_W_m[0], f.u_W_m[1], f.u_W_m[2]);
    const double u_norm_m = u_W_m.norm();
    const Eigen::Vector3d u_sent_W_m = u_norm_m > max_u_m ? Eigen::Vector3d(u_W_m * (max_u_m / u_norm_m)) : u_W_m;
    for (int k = 0; k < 3; ++k) {
      m.p_W_m()[k] = f.p_WC_m[k];
      m.n_W()[k] = f.n_W[k];
      m.p_WE_m()[k] = f.p_WE_m[k];
      m.u_imposed_W_m()[k] = u_sent_W_m[k];
      m.f_W_N()[k] = f.f_W_N[k];
    }
    m.radius_m(radius_m);
    m.depth_m(std::clamp(f.depth_m, -max_u_m, max_u_m));
  }
  const std::int32_t grasped = ClaimedBody(report);
  out.grasped_object_id(grasped >= 0 ? IdOf(models, grasped) : std::string());
  out.simulating(false);
  out.simulated_object_id("");
  for (int b = 0; b < report.num_bodies; ++b) {
    if (owned < 0 || report.bodies[b].object != owned) continue;
    out.simulating(true);
    out.simulated_object_id(IdOf(models, owned));
    for (int k = 0; k < 3; ++k) {
      out.p_WO_m()[k] = report.bodies[b].p_WO_m[k];
      out.v_WO_m_per_s()[k] = report.bodies[b].v_WO_m_per_s[k];
    }
    for (int k = 0; k < 4; ++k) out.q_WO_wxyz()[k] = report.bodies[b].q_WO_wxyz[k];
  }
  return active || out.simulating() || grasped >= 0;
}

}  // namespace handshare::haptic
