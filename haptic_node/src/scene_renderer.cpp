#include "handshare/haptic/scene_renderer.hpp"

#include <algorithm>
#include <cmath>

#include "handshare/common/clock.hpp"

namespace handshare::haptic {

SceneRenderer::SceneRenderer(const scene::Scene& scene, const world::SceneModelsOptions& options,
                             common::SessionClock clock)
    : scene_(scene),
      clock_(clock),
      models_(world::BuildSceneModels(scene, options)),
      controls_(controls::MakeControls(scene)),
      fingertip_radius_m_(options.fingertip_radius_m),
      scripted_(scene_, models_) {
  for (auto& f : f_controls_) f.setZero();
  // A hand on a control when this world appears (it pressed the arrow that brought it here, at
  // the same place) must leave before it can actuate it.
  controls_.SetGuardFirstVisits(true);
  for (const auto& d : models_.deformables) {
    if (const auto id = models_.Find(d.object_id); id >= 0) deformables_.push_back(id);
  }
}

void SceneRenderer::PlaceControl(const std::string& id, std::int32_t index, bool engaged) {
  if (controls::Control* c = controls_.Find(id)) c->ApplyState(index, engaged);
}

bool SceneRenderer::SetControlState(const std::string& id, std::int32_t index, bool engaged) noexcept {
  ControlCommand command;
  const std::size_t n = std::min(id.size(), command.id.size() - 1);
  std::copy_n(id.data(), n, command.id.data());
  command.index = index;
  command.engaged = engaged;
  return control_in_.Push(command);
}

const std::string& SceneRenderer::IdOf(std::int32_t object) const noexcept {
  static const std::string kNone;
  return object >= 0 && object < static_cast<std::int32_t>(models_.ids.size()) ? models_.ids[object] : kNone;
}

void SceneRenderer::PlaceBody(const std::string& id, const Eigen::Isometry3d& X_WO) {
  const auto object = models_.Find(id);
  if (object >= 0) models_.world->SetPose(object, X_WO);
}

void SceneRenderer::WriteLoads(const contact::HapticWorld& world) noexcept {
  DeformableLoads& out = loads_.WriteSlot();
  out.step_ns = common::SteadyNowNs();
  out.count = 0;
  for (const contact::ObjectId object : deformables_) {
    if (out.count >= DeformableLoads::kMaxObjects) break;
    const fem::ContactSolver* solver = world.contact_solver(object);
    if (solver == nullptr || solver->num_unique() == 0) continue;
    auto& item = out.items[out.count++];
    item.object = object;
    const Eigen::Matrix3d R = world.pose(object).linear();
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) item.R_WO[3 * r + c] = R(r, c);
    }
    const auto loads = solver->loads();
    if (loads.size() > static_cast<std::size_t>(DeformableLoads::kMaxLoads)) {
      item.num_loads = -1;
      continue;
    }
    item.num_loads = static_cast<std::int32_t>(loads.size());
    for (std::size_t l = 0; l < loads.size(); ++l) {
      item.loads[l].slot = loads[l].slot;
      item.loads[l].f_N = contact::ToVec3(loads[l].f_N);
    }
  }
  loads_.Publish();
}

void SceneRenderer::ReleaseAll() noexcept {
  ContactReport& r = reports_.WriteSlot();
  r = ContactReport{};
  r.seq = ++seq_;
  reports_.Publish();
  PostReport(r);
}

namespace {
double Distance(const contact::Vec3& a, const contact::Vec3& b) noexcept {
  return (contact::AsVector(a) - contact::AsVector(b)).norm();
}
/// session::PastWeber's test, on the values the contact set carries: |now - sent| beyond
/// max(weber |sent|, floor), less a part in 10^9 for the rounding of another order of sums.
bool PastWeber(const Eigen::Vector3d& sent, const Eigen::Vector3d& now, double weber, double floor) noexcept {
  return (now - sent).norm() > (1.0 - 1e-9) * std::max(weber * sent.norm(), floor);
}
/// The imposed displacement as dds::EncodeFingerContact sends it (clamped to max_m).
Eigen::Vector3d AsSent(const contact::Vec3& u, double max_m) noexcept {
  const Eigen::Vector3d v = contact::AsVector(u);
  const double n = v.norm();
  return n > max_m ? Eigen::Vector3d(v * (max_m / n)) : v;
}
const ContactReport::Body* FindBody(const ContactReport& r, std::int32_t object) noexcept {
  for (int b = 0; b < r.num_bodies; ++b) {
    if (r.bodies[b].object == object) return &r.bodies[b];
  }
  return nullptr;
}
}  // namespace

bool WorthAWakeUp(const SentReference& sent, const ContactReport& now, std::uint64_t now_ns) noexcept {
  if (!sent.valid || !(sent.weber > 0.0)) return true;
  for (int f = 0; f < kFingers; ++f) {
    const contact::FingerContact& a = sent.report.fingers[f];
    const contact::FingerContact& b = now.fingers[f];
    if (a.object != b.object || (b.active() && a.node != b.node)) return true;
    if (!b.active()) continue;
    // A finger on a dynamic body: which body the hand claims depends on the forces on it
    // (ClaimedBody: a grasp, the strongest touch), so every report may change the claim.
    if (FindBody(now, b.object) != nullptr) return true;
    if (b.node < 0) continue;  // a fixed rigid body or a control: only that the finger is there counts
    if (PastWeber(contact::AsVector(a.f_O_N), contact::AsVector(b.f_O_N), sent.weber, sent.force_floor_N) ||
        PastWeber(AsSent(a.u_O_m, sent.max_displacement_m), AsSent(b.u_O_m, sent.max_displacement_m), sent.weber,
                  sent.displacement_floor_m) ||
        Distance(a.p_OC_m, b.p_OC_m) > (1.0 - 1e-9) * sent.position_m) {
      return true;
    }
  }
  if (sent.simulated < 0) return false;
  // The simulated body against where receivers reckon it: half the deadband's thresholds, as
  // the bridge offers the report a little later than the step made it (a longer reckoning).
  const ContactReport::Body* was = FindBody(sent.report, sent.simulated);
  const ContactReport::Body* is = FindBody(now, sent.simulated);
  if (was == nullptr || is == nullptr) return true;
  const double age_s = now_ns > sent.sent_ns ? 1e-9 * static_cast<double>(now_ns - sent.sent_ns) : 0.0;
  const double t = std::clamp(age_s, 0.0, sent.max_reckoning_s);
  const Eigen::Vector3d reckoned = contact::AsVector(was->p_WO_m) + t * contact::AsVector(was->v_WO_m_per_s);
  if ((reckoned - contact::AsVector(is->p_WO_m)).norm() > 0.5 * sent.position_m) return true;
  double dot = 0.0;
  for (int k = 0; k < 4; ++k) dot += was->q_WO_wxyz[k] * is->q_WO_wxyz[k];
  return 2.0 * std::acos(std::min(1.0, std::abs(dot))) > 0.5 * sent.angle_rad;
}

void SceneRenderer::PostReport(const ContactReport& r) noexcept {
  if (!wake_) return;
  bool changed = false;
  for (int f = 0; f < kFingers; ++f) {
    changed |= r.fingers[f].object != touched_[f];
    touched_[f] = r.fingers[f].object;
  }
  if (changed) {
    wake_->Post();
    return;
  }
  if (!report_wake_.load(std::memory_order_relaxed)) return;
  sent_in_.Read(sent_);  // the bridge's newest, if any is new
  if (WorthAWakeUp(sent_, r, r.step_ns)) {
    wake_->Post();
  } else {
    wakes_spared_.fetch_add(1, std::memory_order_relaxed);
  }
}

void SceneRenderer::PostMotion(const DeviceReading& reading, std::uint64_t now_ns) noexcept {
  const double threshold_m = motion_wake_m_.load(std::memory_order_relaxed);
  if (!wake_ || !(threshold_m > 0.0)) return;
  if (motion_due_) {
    // The step before moved the hand, and its snapshot is out: the bridge can take it.
    motion_due_ = false;
    motion_posted_ns_ = now_ns;
    motion_posted_.store(true, std::memory_order_release);
    wake_->Post();
  }
  if (motion_from_set_ && now_ns - motion_posted_ns_ < motion_gap_ns_.load(std::memory_order_relaxed)) return;
  double moved_m = motion_from_set_ ? (reading.p_WH - motion_from_[0]).norm() : 2.0 * threshold_m;
  for (int f = 0; f < kFingers; ++f) {
    if (HasFinger(reading.finger_mask, f)) moved_m = std::max(moved_m, (reading.p_WE[f] - motion_from_[f + 1]).norm());
  }
  if (!(moved_m > threshold_m)) return;  // NaN included: the loop's checks keep such readings out
  motion_from_[0] = reading.p_WH;
  for (int f = 0; f < kFingers; ++f) motion_from_[f + 1] = reading.p_WE[f];
  motion_from_set_ = true;
  motion_due_ = true;
}

void SceneRenderer::Render(double /*t_s*/, double dt_s, std::uint64_t now_ns, const DeviceReading& reading,
                           std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept {
  auto& world = *models_.world;
  // 0. A hand that moved: the bridge's wake-up, so that its state reaches the screens at once.
  PostMotion(reading, now_ns);
  // 1. Objects that move by themselves (the Daphnia swims, its body beats), on the session's
  // clock.
  if (!scripted_.empty()) scripted_.Apply(world, clock_.Now_s());
  // 1b. Bodies simulated elsewhere (another user owns them, or the world server): follow.
  followed_in_.Read(followed_);
  if (followed_.count > 0) {
    for (int i = 0; i < std::min(followed_.count, kMaxReportedBodies); ++i) {
      const auto& b = followed_.items[i];
      if (b.object < 0 || b.object >= world.num_objects()) continue;
      Eigen::Isometry3d X;
      if (!contact::ToPose(b.p_WO_m, b.q_WO_wxyz, X)) continue;
      Eigen::Vector3d v = contact::AsVector(b.v_WO_m_per_s);
      if (!v.allFinite()) v.setZero();
      const double age_s = now_ns > b.received_ns ? 1e-9 * static_cast<double>(now_ns - b.received_ns) : 0.0;
      X.translation() += std::min(age_s, FollowedBodies::kMaxDeadReckoning_s) * v;
      world.SetPose(b.object, X);
      world.SetVelocity(b.object, v, Eigen::Vector3d::Zero());
    }
  }
  // 2. The other hands' contacts (newest set; kept until a newer one arrives), faded by their
  // age at this step: a silent peer's contacts ramp out at the haptic rate even while the
  // bridge is late with the next hand-over. A faded-out one leaves the solve.
  if (remote_in_.Read(remote_) && remote_.newest_stamp_ns != peer_stamp_ns_) {
    peer_stamp_ns_ = remote_.newest_stamp_ns;
    peer_seen_ns_ = common::SteadyNowNs();
  }
  const std::size_t n_received = static_cast<std::size_t>(std::clamp(remote_.count, 0, kMaxRemoteContacts));
  const std::size_t n_remote = peer_fade_.Step({remote_.items, n_received}, remote_.fade, dt_s, now_ns,
                                               remote_contacts_, remote_from_);
  // The network coupling's passivity controller holds back what a late displacement would
  // put into the body beyond what the peer put in at its end (contact/coupling_passivity.hpp).
  passivity_.BeginStep(dt_s, remote_.fade.rate_per_s());
  for (std::size_t j = 0; j < n_remote; ++j) {
    passivity_.Admit(remote_.items[remote_from_[j]], remote_contacts_[j]);
  }
  // 3. Contacts: rigid, dynamic and deformable objects, all hands on a deformable together;
  // only the fingertips the device has (packed: tip i is finger tip_finger_[i]).
  std::size_t n_tips = 0;
  for (int f = 0; f < kFingers; ++f) {
    if (!HasFinger(reading.finger_mask, f)) continue;
    tip_finger_[n_tips] = f;
    tips_[n_tips++] = reading.p_WE[f];
  }
  const std::span<const Eigen::Vector3d> tips(tips_.data(), n_tips);
  world.Step(dt_s, tips, {remote_contacts_.data(), n_remote});
  passivity_.Observe(world.remote_forces_O());
  coupling_stats_.Write(passivity_.stats());
  if (load_snapshots_ && ++steps_since_loads_ >= DeformableLoads::kEverySteps) {
    steps_since_loads_ = 0;
    WriteLoads(world);
  }
  // 4. Controls: where the session left them (a state from the world server waits while this
  // hand is at the control), then their own force profiles and events.
  ControlCommand command;
  while (control_in_.Pop(command)) {
    if (controls::Control* c = controls_.Find(command.id.data())) c->RequestState(command.index, command.engaged);
  }
  event_buffer_.Clear();
  controls_.Step(dt_s, tips, fingertip_radius_m_, {f_controls_.data(), n_tips}, event_buffer_);
  for (const auto& e : event_buffer_) {
    if (!events_.Push(e)) dropped_events_.fetch_add(1, std::memory_order_relaxed);
  }
  const auto fingers = world.fingers();
  for (auto& f : f_E_W) f.setZero();
  for (std::size_t i = 0; i < n_tips; ++i) f_E_W[tip_finger_[i]] = fingers[i].f_E_W_N + f_controls_[i];

  // 5. Report for the bridge (contact set, grasp claims, body poses).
  ContactReport& r = reports_.WriteSlot();
  r.seq = ++seq_;
  r.step_ns = common::SteadyNowNs();
  r.peer_stamp_ns = peer_stamp_ns_;
  r.peer_seen_ns = peer_seen_ns_;
  for (auto& c : r.fingers) c = contact::FingerContact{};
  for (std::size_t i = 0; i < n_tips; ++i) {
    const int f = tip_finger_[i];
    r.fingers[f] = fingers[i].contact;
    r.fingers[f].finger = f;
  }
  r.num_bodies = 0;
  for (const auto body : models_.dynamic_bodies) {
    if (r.num_bodies >= kMaxReportedBodies) break;
    auto& b = r.bodies[r.num_bodies++];
    b.object = body;
    contact::FromPose(world.pose(body), b.p_WO_m, b.q_WO_wxyz);
    b.v_WO_m_per_s = contact::ToVec3(world.body_velocity_W(body));
  }
  reports_.Publish();
  // 6. The bridge wakes for a report that may be worth sending (a touch began or ended, or a
  // peer shares an object): no tick between this step and the deadband.
  PostReport(r);
}

}  // namespace handshare::haptic
