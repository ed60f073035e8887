#pragma once
/// The haptic node's bridge thread, as a list of stages: everything between the haptic loop
/// (its own real-time thread) and the session's DDS topics. One Tick() per bridge period
/// (100 Hz by default); each stage is a short function over the bridge's state. Between ticks
/// the coupling stages alone (Couple()) run whenever the haptic step or the contact and object
/// readers post the bridge's wake-up. Private to the node library: it holds DDS writers and
/// readers.
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <deque>
#include <functional>
#include <map>
#include <memory>
#include <ostream>
#include <set>
#include <string>
#include <vector>

#include "bridge_conversions.hpp"
#include "desk_device.hpp"
#include "local_field_dump.hpp"
#include "handshare/common/latency_histogram.hpp"
#include "handshare/common/overload_watch.hpp"
#include "handshare/common/session_clock.hpp"
#include "handshare/common/wakeup.hpp"
#include "handshare/dds/loop_traffic.hpp"
#include "handshare/dds/messages.hpp"
#include "handshare/haptic/haptic_loop.hpp"
#include "handshare/haptic/haptic_node.hpp"
#include "handshare/haptic/scene_renderer.hpp"
#include "handshare/session/contact_deadband.hpp"
#include "handshare/dds/name_binding.hpp"
#include "handshare/session/peer_contacts.hpp"
#include "handshare/session/stream_rates.hpp"
#include "handshare/dds/sample_checks.hpp"
#include "handshare/world/scene_models.hpp"

namespace handshare::haptic {

/// One printf-formatted line of the node's log (at most 239 characters).
inline std::string Format(const char* format, auto... args) {
  char line[240];
  std::snprintf(line, sizeof line, format, args...);
  return line;
}

/// Every contact set of the coupling path with its times on this host's steady clock [ns], for
/// bench/net (HapticNodeConfig::coupling_trace_file). Fixed capacity: rows beyond it are not kept.
struct CouplingTrace {
  struct Row {
    char kind;  ///< 'w' written: seq, the step that made it, write() called, returned;
                ///< 't' a peer's taken: its stamp (the sender's write), the take;
                ///< 'u' a peer's first used by the haptic loop: its stamp, that step
    std::uint64_t a, b, c, d;
  };
  static constexpr std::size_t kCapacity = 400'000;
  std::vector<Row> rows;
  void Add(const Row& r) {
    if (rows.size() < rows.capacity()) rows.push_back(r);
  }
};

class HapticBridge {
 public:
  using Clock = std::chrono::steady_clock;
  using Say = std::function<void(const std::string&)>;

  /// trace: where every device state goes as a CSV row (nullptr: none). Not real-time.
  HapticBridge(const HapticNodeConfig& config, Device& device, HapticLoop& loop, dds::Participant& participant,
               std::ostream* trace, Say say);

  /// One bridge period: the stages below, in this order.
  void Tick();
  /// Between ticks: sleeps until the haptic step reports a contact worth offering, a peer's
  /// contact set or an object state arrives (the readers' listeners post; nothing is polled),
  /// or the deadline. True when woken before it: then call Couple().
  bool WaitForCoupling(Clock::time_point deadline) { return wake_->WaitUntil(deadline); }
  /// The coupling stages alone, at once: the newest report, the peers' contact sets and the
  /// bodies' states to the haptic loop (lock-free), this hand's contact set to the deadband,
  /// the hand's control events to the world server.
  void Couple();
  /// How long after this tick the next is due. The bridge period (1 / publish_Hz) while anything
  /// goes at the tick's rate: a finger touches something or a touch's last set is owed, a peer's
  /// contacts are held, a body is owned or held for a hand-over, control events wait, a desk or a
  /// trace or field dump is on, no world yet, or the coupling is polled. Otherwise kIdleTick, or
  /// the viewers' device-state period if that is shorter: what arrives wakes the bridge anyway
  /// (contact sets, object states, desk input; scene and control states ask for a tick at once,
  /// TickAsked), so a bridge with nothing to carry no longer wakes 100 times a second
  /// (docs/network.md, "CPU per node").
  Clock::duration TickPeriod() const;
  static constexpr std::chrono::milliseconds kIdleTick{50};
  /// A scene or control state arrived since the last Tick (their readers' listeners say so
  /// with the coupling woken): tick now rather than at the idle period's end.
  bool TickAsked() const { return tick_asked_->load(std::memory_order_acquire); }
  /// Writes the coupling trace (HapticNodeConfig::coupling_trace_file) if one was asked for.
  void WriteCouplingTrace() const;

  std::uint64_t device_states_published() const { return device_states_published_; }
  /// Of those, the ones sent on a motion wake rather than at a tick.
  std::uint64_t device_states_on_motion() const { return device_states_on_motion_; }
  /// A hand (base or fingertip) that moved this far since its last motion wake wakes the bridge
  /// [m]: under a pixel of a 1280 x 720 user's view (0.75 mm, docs/devices.md).
  static constexpr double kMotionWake_m = 0.5e-3;
  /// Whether a scene state of the session's world server has arrived since this bridge began.
  bool heard_world_server() const { return scene_revision_ != 0; }
  std::uint64_t control_events_sent() const { return control_events_sent_; }
  /// --device desk: the person's inputs taken from their view.
  std::uint64_t desk_inputs() const { return desk_inputs_; }
  /// Received samples refused by the checks (session/sample_checks.hpp), per topic.
  const dds::DroppedSamples& dropped() const { return dropped_; }
  /// Age of the peers' contact sets when this bridge took them: their sender's stamp (its
  /// steady clock: meaningful for peers on this host only) to the take.
  const common::LatencyHistogram& peer_contact_age() const { return peer_age_; }
  /// The same up to the haptic step that first used the set (at most one per bridge tick:
  /// a set replaced before the loop used it is not counted).
  const common::LatencyHistogram& peer_contact_loop_age() const { return peer_loop_age_; }
  /// Age of this hand's contact report when its contact set was written (the haptic step
  /// that made it to the write): the sender's part of the node-to-node path.
  const common::LatencyHistogram& contact_report_age() const { return report_age_; }
  /// What the contact-set deadband let through (offered: sets a peer could read).
  const session::ContactSetDeadband& deadband() const { return deadband_; }
  /// What the network coupling's passivity observer and controller did, over every renderer
  /// this bridge has had (contact/coupling_passivity.hpp).
  contact::CouplingPassivityStats coupling_stats() const;
  bool coupling_passivity() const { return config_.coupling_passivity; }
  /// Contact sets written, and how many of them at the full rate (a peer shared an object).
  std::uint64_t contact_sets_sent() const { return contact_sets_sent_; }
  std::uint64_t contact_sets_shared() const { return contact_sets_shared_; }
  /// The bridge's own rate: ticks, and the time from one tick's start to the next's.
  std::uint64_t ticks() const { return ticks_; }
  const common::LatencyHistogram& tick_interval() const { return tick_interval_; }
  /// Whether the bridge fell below half its rate (or stalled 100 ms) for a while: said in the
  /// log when it starts and ends (common::OverloadWatch).
  const common::OverloadWatch& overload() const { return overload_; }

 private:
  // ---- the stages of a tick ----
  /// A new scene revision (another world, or the same world with new gravity) gets a new
  /// renderer, handed to the haptic loop; dynamic bodies keep their poses in the same world.
  void ApplySceneChange();
  /// The world server's control states: kept per control, and handed to the renderer of
  /// their world (another user moved a control; a rebuilt world starts from them).
  void FollowControlStates();
  /// The renderer's control events, to the world server (reliably). The topic is volatile: an
  /// event written before a reader matched this writer never reaches it, so events wait (at most
  /// kMaxHeldEvents, the oldest dropped and counted beyond) until a reader is matched.
  void ForwardControlEvents();
  static constexpr std::size_t kMaxHeldEvents = 256;
  /// The other users' contact sets, on this world's deformables, handed to the loop (always at
  /// a tick, which also lets vanished peers expire; between ticks when one was taken).
  void ReceivePeers(bool tick);
  /// Rigid bodies another process simulates: this hand follows their published states (always
  /// at a tick; between ticks when a state arrived or the hand's report changed the hand-over).
  void FollowPeerBodies(bool tick);
  /// The newest haptic snapshot, to viewers (and the trace), at the fastest viewer's frame rate.
  /// moved: on the haptic step's motion wake (SceneRenderer::SetMotionWake), else at a tick.
  void PublishDeviceState(bool moved);
  /// This hand's contacts: while touching, grasping or simulating, and once more at the end,
  /// each when it differs perceptibly from the last one sent or a keepalive is due; at the
  /// bridge's rate while a peer touches the same object, else at the world server's tick.
  void PublishContactSet();
  /// The loop statistics, once a second.
  void PublishStatistics();
  /// --device desk: the person's newest input from their view (this user's DeskInput), handed
  /// to the desk device; says when the hand goes live and when it is released (focus lost,
  /// desk quiet).
  void FollowDeskInput();

  /// This node's field of each touched deformable, to --dump-deformation DIR.
  void DumpLocalFields();
  /// The haptic loop's newest report, if there is one, and its peer set stamps into
  /// peer_loop_age_. Needs a renderer.
  void TakeReport();
  /// Builds the renderer of one scene state and hands it to the loop.
  void AdoptScene(const msg::SceneState& state);

  HapticNodeConfig config_;
  // Posted by the haptic step and the contact and object readers' listeners (before the
  // readers: the listeners hold it too).
  std::shared_ptr<common::Wakeup> wake_ = std::make_shared<common::Wakeup>();
  std::shared_ptr<std::atomic<bool>> tick_asked_ = std::make_shared<std::atomic<bool>>(false);
  Device& device_;
  HapticLoop& loop_;
  std::ostream* trace_;
  Say say_;
  world::SceneModelsOptions models_options_;

  dds::Writer<msg::DeviceState> state_writer_;
  dds::Writer<msg::LoopStatistics> stats_writer_;
  dds::Writer<msg::ContactSet> contact_writer_;
  dds::Writer<msg::ControlEvent> event_writer_;
  dds::Reader<msg::SceneState> scene_reader_;
  dds::Reader<msg::ContactSet> contact_reader_;
  // Present users and the participants that announced them: a contact set in a present
  // peer's name from another participant is dropped (dds/name_binding.hpp).
  dds::Reader<msg::MemberInfo> member_reader_;
  dds::NameBinding names_;
  std::set<std::string> peers_heard_;  // peers whose contact sets were taken (each named once)
  dds::Reader<msg::ObjectState> object_reader_;
  dds::Reader<msg::ControlState> control_reader_;  // empty: a keystore without the grant
  DeskDevice* desk_ = nullptr;                      // --device desk, else none
  dds::Reader<msg::DeskInput> desk_reader_;         // empty without a desk (or the grant)
  std::uint64_t desk_inputs_ = 0;                   // taken and posted
  std::uint64_t desk_last_ns_ = 0;                  // when the newest was taken
  bool desk_live_ = false;                          // what was last said: live or released
  std::map<std::string, msg::ControlState> control_states_;  // by control id, newest

  std::shared_ptr<SceneRenderer> renderer_;  ///< the bridge's handle; the loop holds its own
  std::uint32_t scene_revision_ = 0;
  double server_tick_Hz_ = 0.0;  ///< how often the world server reads contact sets (0: not said)
  common::SessionClock session_clock_;
  ContactReport report_;
  bool have_report_ = false;
  bool last_sent_active_ = false;
  session::PeerContacts peers_;    ///< the other users' newest contact sets (faded when silent)
  ReceivedBodies bodies_;          ///< published rigid-body states, followed unless owned here
  HandOverHold hand_over_;         ///< an owned body let go of while a peer grasps it
  std::int32_t owned_ = -1;        ///< OwnedBody() of this tick (FollowPeerBodies)

  msg::DeviceState state_msg_;
  msg::LoopStatistics stats_msg_;
  dds::LoopTraffic stats_traffic_;  ///< the statistics' deadline misses and bytes sent per second
  msg::ContactSet contacts_msg_;
  session::ContactSetDeadband deadband_;
  // The coupling passivity of the renderers before this one (summed), and of this one.
  contact::CouplingPassivityStats coupling_before_{}, coupling_now_{};
  session::StreamPacer state_pacer_;
  session::StreamPacer contact_pacer_;
  std::uint64_t contact_sets_sent_ = 0;
  std::uint64_t contact_sets_shared_ = 0;
  std::uint64_t ticks_ = 0;
  std::uint64_t last_tick_ns_ = 0;
  common::LatencyHistogram tick_interval_;
  // Below half its rate (the bar: 50 Hz of 100) or a 100 ms stall: overloaded.
  common::OverloadWatch overload_{"the bridge", common::OverloadLimits{config_.publish_Hz, 0.5 * config_.publish_Hz}};
  Clock::time_point next_stats_;
  std::uint64_t device_states_published_ = 0;
  std::uint64_t device_states_on_motion_ = 0;
  std::uint64_t moved_sent_ns_ = 0;  // steady clock of the last device state sent as the hand moved
  double state_rate_Hz_ = 0.0;       // the device states' rate at the last tick (0: no viewer)
  std::uint64_t control_events_sent_ = 0;
  std::deque<msg::ControlEvent> held_events_;  // taken, not yet written: no reader matched
  std::uint64_t held_events_dropped_ = 0;
  dds::DroppedSamples dropped_;
  common::LatencyHistogram peer_age_;
  common::LatencyHistogram peer_loop_age_;
  common::LatencyHistogram report_age_;
  std::uint64_t newest_peer_stamp_ns_ = 0;
  std::uint64_t last_loop_peer_stamp_ns_ = 0;
  std::unique_ptr<LocalFieldDump> field_dump_;  // --dump-deformation
  CouplingTrace trace_rows_;                     // coupling_trace_file
};

}  // namespace handshare::haptic
