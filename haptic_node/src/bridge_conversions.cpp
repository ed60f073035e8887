#include "bridge_conversions.hpp"

#include <algorithm>
#include <bit>
#include <cmath>

#include "handshare/dds/contact_codec.hpp"
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
  std::copy_n(s.p_WH_m, 3, out.p_WH_m().begin());
  std::copy_n(s.q_WH_wxyz, 4, out.q_WH_wxyz().begin());
  for (int i = 0; i < kFingers; ++i) {
    std::copy_n(s.p_WE_m[i], 3, out.p_WE_m()[i].begin());
    std::copy_n(s.f_E_W_N[i], 3, out.f_E_W_N()[i].begin());
  }
  out.fingertip_radius_m(s.fingertip_radius_m);
  std::copy_n(s.q_hand_rad, common::kHandJoints, out.q_hand_rad().begin());
  std::copy_n(s.q_arm_rad, common::kArmJoints, out.q_arm_rad().begin());
  out.fault(s.fault);
  out.absent_fingers(static_cast<std::uint8_t>(kEveryFinger & ~s.finger_mask));
}

msg::DeviceCaps ToDeviceCaps(const DeviceCapabilities& c) {
  msg::DeviceCaps out;
  out.contact_points(static_cast<std::uint8_t>(std::popcount(static_cast<unsigned>(c.finger_mask))));
  out.finger_mask(c.finger_mask);
  out.max_force_N(static_cast<float>(c.max_fingertip_force_N));
  out.workspace_radius_m(static_cast<float>(c.workspace_radius_m));
  out.rate_Hz(static_cast<float>(c.control_rate_Hz));
  out.gripper(c.has_gripper);
  return out;
}

DeskTarget ToDeskTarget(const msg::DeskInput& in, std::uint64_t received_ns) {
  DeskTarget t;
  for (int k = 0; k < 3; ++k) t.p_WH_m[k] = in.p_WH_m()[k];
  for (int k = 0; k < 4; ++k) t.q_WH_wxyz[k] = in.q_WH_wxyz()[k];
  for (int i = 0; i < kFingers; ++i) t.closure[i] = in.closure()[i];
  t.focused = in.focused();
  t.received_ns = received_ns;
  return t;
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
    on_body[i].active = f.active() && f.object == object;
    for (int k = 0; k < 3; ++k) on_body[i].f_W_N[k] = f.f_O_N[k];  // one frame (the body's) for all
  }
  return world::IsGrasp(on_body, kFingers);
}

std::int32_t ClaimedBody(const ContactReport& r) {
  std::int32_t touched = -1;
  double strongest = 0.0;
  for (int b = 0; b < r.num_bodies; ++b) {
    if (HandGrasps(r, r.bodies[b].object)) return r.bodies[b].object;
    for (const auto& f : r.fingers) {
      if (!f.active() || f.object != r.bodies[b].object) continue;
      const double norm = contact::AsVector(f.f_O_N).norm();
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
      contact::FingerContact c;
      on_body[i].active = fingers[i].object_id().to_string() == object_id && dds::DecodeFingerContact(fingers[i], i, 0, c);
      for (int k = 0; k < 3; ++k) on_body[i].f_W_N[k] = c.f_O_N[k];  // one frame (the body's) for all
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
  item.p_WO_m = at_.p_WO_m;
  item.q_WO_wxyz = at_.q_WO_wxyz;
  item.v_WO_m_per_s = {};
  item.received_ns = now_ns;
  return began;
}

Eigen::Isometry3d PoseOf(const ContactReport::Body& body) { return contact::ToPose(body.p_WO_m, body.q_WO_wxyz); }

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
    item.p_WO_m = st.p_WO_m();
    item.q_WO_wxyz = st.q_WO_wxyz();
    item.v_WO_m_per_s = st.v_WO_m_per_s();
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
    if (remote.count >= kMaxRemoteContacts || models.world->contact_solver(c.contact.object) == nullptr) return;
    remote.items[remote.count++] = c;
  });
  return remote;
}

bool ToContactSet(const ContactReport& report, const world::SceneModels& models, std::int32_t owned,
                  double radius_m, msg::ContactSet& out) {
  // A fingertip far inside an object (pushed through it, or after a stall) goes out with its
  // displacement and depth clamped to what receivers accept (dds::EncodeFingerContact).
  const double max_u_m = dds::SampleBounds{}.max_displacement_m;
  bool active = false;
  for (int i = 0; i < kFingers; ++i) {
    const auto& f = report.fingers[i];
    active |= f.active();
    dds::EncodeFingerContact(f, IdOf(models, f.object), radius_m, max_u_m, out.fingers()[i]);
  }
  const std::int32_t grasped = ClaimedBody(report);
  out.grasped_object_id(grasped >= 0 ? IdOf(models, grasped) : std::string());
  out.simulating(false);
  out.simulated_object_id("");
  for (int b = 0; b < report.num_bodies; ++b) {
    if (owned < 0 || report.bodies[b].object != owned) continue;
    out.simulating(true);
    out.simulated_object_id(IdOf(models, owned));
    out.p_WO_m(report.bodies[b].p_WO_m);
    out.v_WO_m_per_s(report.bodies[b].v_WO_m_per_s);
    out.q_WO_wxyz(report.bodies[b].q_WO_wxyz);
  }
  return active || out.simulating() || grasped >= 0;
}

SentReference ToSentReference(const ContactReport& report, const msg::ContactSet& sent, std::int32_t owned,
                              const session::DeadbandConfig& deadband, std::uint64_t sent_ns) {
  SentReference r;
  r.valid = true;
  r.report = report;
  r.simulated = sent.simulating() ? owned : -1;
  r.sent_ns = sent_ns;
  r.weber = deadband.weber;
  r.force_floor_N = deadband.force_floor_N;
  r.displacement_floor_m = deadband.displacement_floor_m;
  r.position_m = deadband.position_m;
  r.angle_rad = deadband.angle_rad;
  r.max_reckoning_s = session::kMaxReckoning_s;
  r.max_displacement_m = dds::SampleBounds{}.max_displacement_m;  // as ToContactSet clamps
  return r;
}

}  // namespace handshare::haptic
