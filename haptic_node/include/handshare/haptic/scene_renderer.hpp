#pragma once
/// The force renderer of a haptic node: one scene's haptic models (rigid, dynamic and
/// deformable objects through handshare::contact, controls through handshare::controls),
/// stepped by the haptic thread. The bridge thread builds it (not real-time), hands it to the
/// loop, feeds it the other hands' contacts and drains what it reports (contacts, control
/// events), all through lock-free, fixed-size channels.
#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "handshare/common/session_clock.hpp"
#include "handshare/common/spsc_queue.hpp"
#include "handshare/common/triple_buffer.hpp"
#include "handshare/common/wakeup.hpp"
#include "handshare/controls/controls.hpp"
#include "handshare/haptic/force_renderer.hpp"
#include "handshare/contact/coupling_passivity.hpp"
#include "handshare/contact/peer_contact.hpp"
#include "handshare/world/scene_models.hpp"
#include "handshare/world/scripted_motion.hpp"

namespace handshare::haptic {

inline constexpr int kMaxRemoteContacts = 40;  // 8 hands x 5 fingers
inline constexpr int kMaxReportedBodies = 8;

/// What the haptic thread reports each step (trivially copyable).
struct ContactReport {
  std::uint64_t seq = 0;
  std::uint64_t step_ns = 0;  ///< the step that made it (steady clock) [ns]
  /// Each finger's main contact as the hand shares it (contact::FingerContact: frame O, force
  /// on the object; object -1: touching nothing).
  contact::FingerContact fingers[kFingers];
  struct Body {
    std::int32_t object = -1;
    contact::Vec3 p_WO_m{};
    contact::QuatWxyz q_WO_wxyz{1, 0, 0, 0};
    contact::Vec3 v_WO_m_per_s{};
  } bodies[kMaxReportedBodies];
  std::int32_t num_bodies = 0;
  /// The newest peer contact set this loop has used: its sender's stamp (RemoteContacts::
  /// newest_stamp_ns) and the step that first used it (steady clock) [ns]; 0 before any.
  std::uint64_t peer_stamp_ns = 0;
  std::uint64_t peer_seen_ns = 0;
};

/// Other hands' contacts on this scene's objects (trivially copyable), as received: the
/// haptic thread fades each by its age at every step (fade, items[i].received_ns), so the fade
/// moves at the haptic rate however seldom the bridge hands a new set over.
struct RemoteContacts {
  std::int32_t count = 0;
  contact::PeerContact items[kMaxRemoteContacts];
  contact::PeerFade fade;  ///< the fade law (session::PeerContacts::fade())
  /// The sender's stamp (ContactSet::stamp_ns) of the newest peer set received so far [ns].
  std::uint64_t newest_stamp_ns = 0;
};

/// Dynamic bodies another process simulates (owned by another user, or free and simulated by
/// the world server): this hand follows their published poses (trivially copyable). Between
/// samples (published at display rate) each haptic step moves the body on at its published
/// velocity from where it was at the sample's arrival (dead reckoning, at most
/// kMaxDeadReckoning_s ahead), so a moving body glides instead of jumping every ~16 ms, and
/// the body carries that velocity (contact damping, and a hand-over keeps its motion).
struct FollowedBodies {
  static constexpr double kMaxDeadReckoning_s = 0.1;
  std::int32_t count = 0;
  struct Item {
    std::int32_t object = -1;
    contact::Vec3 p_WO_m{};
    contact::QuatWxyz q_WO_wxyz{1, 0, 0, 0};
    contact::Vec3 v_WO_m_per_s{};
    std::uint64_t received_ns = 0;  ///< common::SteadyNowNs() when the sample arrived
  } items[kMaxReportedBodies];
};

/// The loads of this hand's solve of each touched deformable (trivially copyable): what the
/// bridge turns into the local surface field (--dump-deformation). The haptic thread writes it
/// every kEverySteps steps while enabled.
struct DeformableLoads {
  static constexpr int kMaxObjects = 3;
  static constexpr int kMaxLoads = 384;
  static constexpr int kEverySteps = 20;
  std::uint64_t step_ns = 0;  ///< the step that made it (steady clock) [ns]
  std::int32_t count = 0;
  struct Item {
    std::int32_t object = -1;
    std::int32_t num_loads = 0;  ///< -1: more than kMaxLoads (not copied)
    double R_WO[9] = {};         ///< the object's orientation, row-major
    struct Load {
      std::int32_t slot = -1;  ///< compliance slot (fem::NodeLoad)
      contact::Vec3 f_N{};     ///< force on the object, frame O [N]
    } loads[kMaxLoads];
  } items[kMaxObjects];
};

/// What the bridge last sent, for the haptic step to judge its own reports by (SceneRenderer::
/// SetSentReference): the report that made the contact set the bridge sent last, the body that
/// set simulates, when it went, and the deadband's thresholds (session::DeadbandConfig's, as
/// plain numbers: this layer has no middleware). Trivially copyable.
struct SentReference {
  bool valid = false;           ///< false: nothing sent yet (every report is worth a wake-up)
  ContactReport report;         ///< the report the sent set was made from
  std::int32_t simulated = -1;  ///< the body the set simulates (the hand owns it), or -1
  std::uint64_t sent_ns = 0;    ///< steady clock [ns]
  double weber = 0.0;           ///< 0: the deadband is off, every set goes out
  double force_floor_N = 0.0;
  double displacement_floor_m = 0.0;
  double position_m = 0.0;
  double angle_rad = 0.0;
  double max_reckoning_s = 0.0;
  double max_displacement_m = 0.0;  ///< the imposed displacement's clamp on the wire
};

/// Whether the deadband may send the contact set of `now`, judged against the sent set's report
/// by the deadband's own tests on the values the set carries (session::PerceptibleChange:
/// Weber's law with its floor on each finger's force and imposed displacement, the contact
/// point, a finger on or off or on another object or node), the simulated body against where
/// receivers reckon it at half the deadband's thresholds, and always while a finger touches a
/// dynamic body (the claim on it depends on the forces). So no change the deadband would send
/// goes without a wake-up, and a still press, which it would not send, wakes nothing. Pure,
/// noexcept, no allocation: the haptic thread's.
bool WorthAWakeUp(const SentReference& sent, const ContactReport& now, std::uint64_t now_ns) noexcept;

class SceneRenderer final : public ForceRenderer {
 public:
  /// Builds the models of `scene` (deformables from the compliance cache). Periodic motions and
  /// beats run
  /// on the session's `clock` (the world server's origin). Not real-time.
  SceneRenderer(const scene::Scene& scene, const world::SceneModelsOptions& options,
                common::SessionClock clock = {});

  void Render(double t_s, double dt_s, std::uint64_t now_ns, const DeviceReading& reading,
              std::array<Eigen::Vector3d, kFingers>& f_E_W) noexcept override;
  void ReleaseAll() noexcept override;

  // ---- bridge side ----
  const scene::Scene& scene() const noexcept { return scene_; }
  const world::SceneModels& models() const noexcept { return models_; }
  /// World object index -> scene object id ("" if out of range).
  const std::string& IdOf(std::int32_t object) const noexcept;
  bool TakeReport(ContactReport& out) noexcept { return reports_.Read(out); }
  /// The bridge's wake-up: the haptic step posts it (a non-blocking futex wake, no lock, no
  /// allocation) when a finger starts or stops touching an object, and while SetReportWake(true)
  /// after every step whose report the deadband may send, so such a report reaches the bridge
  /// within the step that made it. Not thread-safe: call before SetRenderer; nullptr: never posted.
  void SetWakeup(std::shared_ptr<common::Wakeup> wake) noexcept { wake_ = std::move(wake); }
  /// Bridge side, any time: post after every step whose report the deadband may send (a peer's
  /// loop solves an object with this hand's contacts; SetSentReference), or only on touch changes.
  void SetReportWake(bool every_step) noexcept { report_wake_.store(every_step, std::memory_order_relaxed); }
  /// Bridge side, after each contact set it sends: what it sent. While SetReportWake(true) the
  /// step then posts only for a report WorthAWakeUp against it (a held press: none), instead of
  /// after every step; the bridge's ticks still offer every tick's report (keepalives).
  void SetSentReference(const SentReference& sent) noexcept {
    sent_in_.WriteSlot() = sent;
    sent_in_.Publish();
  }
  /// Steps whose report a peer would read but that posted no wake-up (WorthAWakeUp false).
  std::uint64_t wakes_spared() const noexcept { return wakes_spared_.load(std::memory_order_relaxed); }
  /// Bridge side, any time: post the wake-up, too, when the hand (its base or a fingertip it
  /// has) has moved more than threshold_m since the last such post, and no sooner than
  /// min_gap_ns after it. The post comes one step after the step that moved the hand, so the
  /// loop has published that step's snapshot by then: a screen that draws this hand gets its
  /// motion without waiting for a tick (docs/devices.md, "Motion to photon"). threshold_m <= 0
  /// (the default): off.
  void SetMotionWake(double threshold_m, std::uint64_t min_gap_ns) noexcept {
    motion_gap_ns_.store(min_gap_ns, std::memory_order_relaxed);
    motion_wake_m_.store(threshold_m, std::memory_order_relaxed);
  }
  /// Bridge side: whether the haptic step posted a motion wake since the last call.
  bool TakeMotion() noexcept { return motion_posted_.exchange(false, std::memory_order_acq_rel); }
  bool TakeEvent(controls::ControlEvent& out) noexcept { return events_.Pop(out); }
  void SetRemote(const RemoteContacts& remote) noexcept { remote_in_.Write(remote); }
  /// The bodies to follow from the next step on (an empty set: this hand simulates them all).
  void SetFollowed(const FollowedBodies& followed) noexcept { followed_in_.Write(followed); }
  /// Places a dynamic body before the renderer is handed to the loop (carry-over of poses
  /// across a rebuild). Not thread-safe: call before SetRenderer.
  void PlaceBody(const std::string& id, const Eigen::Isometry3d& X_WO);
  /// Puts control `id` where the session left it (the world server's control state): at
  /// once, before the renderer is handed to the loop. Not thread-safe: call before SetRenderer.
  void PlaceControl(const std::string& id, std::int32_t index, bool engaged);
  /// The same while the loop runs: applied by the haptic thread at its next step, or, while a
  /// fingertip of this hand is at the control, once it has left. False if the queue is full.
  bool SetControlState(const std::string& id, std::int32_t index, bool engaged) noexcept;
  std::uint64_t dropped_events() const noexcept { return dropped_events_.load(std::memory_order_relaxed); }
  /// The passivity controller on the peers' contacts (on by default; off: observed only).
  /// Not thread-safe: call before SetRenderer.
  void SetCouplingPassivity(bool on) noexcept { passivity_.set_enabled(on); }
  /// What the coupling's passivity observer and controller have seen and done (the haptic
  /// thread publishes it every step). False before the first step.
  bool TakeCouplingStats(contact::CouplingPassivityStats& out) noexcept { return coupling_stats_.Read(out); }
  /// The haptic thread publishes DeformableLoads from now on. Not thread-safe: call before
  /// SetRenderer.
  void EnableLoadSnapshots() noexcept { load_snapshots_ = true; }
  /// The newest DeformableLoads; false if none is new since the last call.
  bool TakeLoads(DeformableLoads& out) noexcept { return loads_.Read(out); }

 private:
  void WriteLoads(const contact::HapticWorld& world) noexcept;
  void PostReport(const ContactReport& r) noexcept;
  void PostMotion(const DeviceReading& reading, std::uint64_t now_ns) noexcept;

  scene::Scene scene_;
  common::SessionClock clock_;
  world::SceneModels models_;
  controls::ControlSet controls_;
  double fingertip_radius_m_;
  world::ScriptedMotion scripted_;  // motions and beats on the session clock
  std::vector<contact::ObjectId> deformables_;                       // world indices (load snapshots)
  // Haptic-thread state, sized here.
  std::array<Eigen::Vector3d, kFingers> f_controls_{};
  // The fingertips the device has, packed (a stylus: one, its index finger), and which finger
  // each is: the world and the controls see only those, with no stand-ins for the others.
  std::array<Eigen::Vector3d, kFingers> tips_{};
  std::array<int, kFingers> tip_finger_{};
  controls::EventBuffer event_buffer_;
  RemoteContacts remote_;
  FollowedBodies followed_;
  std::array<contact::FingerContact, kMaxRemoteContacts> remote_contacts_{};
  std::array<std::int32_t, kMaxRemoteContacts> remote_from_{};  // remote_contacts_[j] is remote_.items[remote_from_[j]]
  contact::CouplingPassivity passivity_;
  contact::PeerFadeStage peer_fade_;
  // Channels.
  common::TripleBuffer<RemoteContacts> remote_in_;
  common::TripleBuffer<FollowedBodies> followed_in_;
  common::TripleBuffer<ContactReport> reports_;
  common::TripleBuffer<contact::CouplingPassivityStats> coupling_stats_;
  bool load_snapshots_ = false;
  int steps_since_loads_ = 0;
  common::TripleBuffer<DeformableLoads> loads_;
  common::SpscQueue<controls::ControlEvent, 256> events_;
  struct ControlCommand {
    std::array<char, 32> id{};  ///< NUL-terminated
    std::int32_t index = -1;
    bool engaged = false;
  };
  common::SpscQueue<ControlCommand, 64> control_in_;
  std::atomic<std::uint64_t> dropped_events_{0};
  std::shared_ptr<common::Wakeup> wake_;
  std::atomic<bool> report_wake_{false};
  common::TripleBuffer<SentReference> sent_in_;  // bridge -> haptic thread
  SentReference sent_;                           // the haptic thread's newest copy
  std::atomic<std::uint64_t> wakes_spared_{0};
  std::array<std::int32_t, kFingers> touched_{-1, -1, -1, -1, -1};  // each finger's object at the last report
  // The motion wake (SetMotionWake): the bridge's settings, the haptic thread's state.
  std::atomic<double> motion_wake_m_{0.0};
  std::atomic<std::uint64_t> motion_gap_ns_{0};
  std::atomic<bool> motion_posted_{false};
  std::array<Eigen::Vector3d, kFingers + 1> motion_from_{};  // hand base, then fingertips, at the last post
  bool motion_from_set_ = false;
  bool motion_due_ = false;  // the last step moved the hand: post at this step
  std::uint64_t motion_posted_ns_ = 0;
  std::uint64_t seq_ = 0;
  std::uint64_t peer_stamp_ns_ = 0;  // the newest peer set used, and the step that first used it
  std::uint64_t peer_seen_ns_ = 0;
};

}  // namespace handshare::haptic
