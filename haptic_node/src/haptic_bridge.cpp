#include "haptic_bridge.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <stdexcept>

#include "handshare/common/clock.hpp"
#include "handshare/haptic/replay.hpp"
#include "handshare/session/control_events.hpp"

namespace handshare::haptic {

HapticBridge::HapticBridge(const HapticNodeConfig& config, Device& device, HapticLoop& loop,
                           dds::Participant& participant, std::ostream* trace, Say say)
    : config_(config),
      device_(device),
      loop_(loop),
      trace_(trace),
      say_(std::move(say)),
      state_writer_(dds::MakeWriter<msg::DeviceState>(participant, dds::topics::kDeviceState)),
      stats_writer_(dds::MakeWriter<msg::LoopStatistics>(participant, dds::topics::kLoopStatistics)),
      contact_writer_(dds::MakeWriter<msg::ContactSet>(participant, dds::topics::kContactSet)),
      event_writer_(dds::MakeWriter<msg::ControlEvent>(participant, dds::topics::kControlEvent)),
      scene_reader_(dds::MakeReader<msg::SceneState>(participant, dds::topics::kSceneState)),
      contact_reader_(dds::MakeReader<msg::ContactSet>(participant, dds::topics::kContactSet)),
      member_reader_(dds::NameBinding::MakeMemberReader(participant, say_)),
      object_reader_(dds::MakeReader<msg::ObjectState>(participant, dds::topics::kObjectState)),
      control_reader_(dds::MakeReaderIfGranted<msg::ControlState>(participant, dds::topics::kControlState, say_,
                                                                  "controls start at rest in every world")),
      desk_(dynamic_cast<DeskDevice*>(&device)),
      desk_reader_(desk_ == nullptr ? dds::Reader<msg::DeskInput>{}
                                    : dds::MakeReaderIfGranted<msg::DeskInput>(participant, dds::topics::kDeskInput, say_,
                                                                               "the desk's hand stays released")),
      stats_traffic_(participant),
      deadband_(session::DeadbandConfig{.weber = config.deadband_weber}),
      state_pacer_(config.publish_Hz),
      contact_pacer_(config.publish_Hz),
      next_stats_(Clock::now() + std::chrono::seconds(1)) {
  models_options_.cache_dir =
      config_.cache_dir.empty() ? world::DefaultCacheDir() : std::filesystem::path(config_.cache_dir);
  models_options_.fingertip_radius_m = device_.capabilities().fingertip_radius_m;
  if (!config_.dump_dir.empty()) {
    field_dump_ = std::make_unique<LocalFieldDump>(config_.dump_dir, config_.user, std::chrono::milliseconds(100));
  }
  models_options_.max_force_N = device_.capabilities().max_fingertip_force_N;
  state_msg_.user(config_.user);
  state_msg_.session(config_.where.session);
  contacts_msg_.user(config_.user);
  contacts_msg_.session(config_.where.session);
  stats_msg_.node("haptic_node/" + config_.user);
  stats_msg_.session(config_.where.session);
  if (!config_.coupling_trace_file.empty()) trace_rows_.rows.reserve(CouplingTrace::kCapacity);
  if (config_.coupling_on_wake) {
    // The listeners only signal; this bridge's thread takes the samples (Couple).
    contact_reader_.OnDataAvailable([wake = wake_] { wake->Post(); });
    object_reader_.OnDataAvailable([wake = wake_] { wake->Post(); });
    // The person at the desk: their input reaches the hand between ticks too (motion to photon,
    // docs/devices.md).
    if (desk_ != nullptr && desk_reader_) desk_reader_.OnDataAvailable([wake = wake_] { wake->Post(); });
    // A new world or a control's new state is the tick's work: asked for at once, so that an
    // idle bridge (TickPeriod) does not hold it back for its idle period.
    auto ask_tick = [wake = wake_, asked = tick_asked_] {
      asked->store(true, std::memory_order_release);
      wake->Post();
    };
    scene_reader_.OnDataAvailable(ask_tick);
    if (control_reader_) control_reader_.OnDataAvailable(ask_tick);
  }
}

HapticBridge::Clock::duration HapticBridge::TickPeriod() const {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / config_.publish_Hz));
  // Polled, every coupling stage waits for a tick; a trace or a field dump records at each.
  if (!config_.coupling_on_wake || trace_ != nullptr || field_dump_ || !renderer_ || desk_ != nullptr) return period;
  if (last_sent_active_ || !peers_.sets().empty() || owned_ >= 0 || hand_over_.held() >= 0 || !held_events_.empty()) {
    return period;
  }
  if (have_report_) {
    for (const auto& f : report_.fingers) {
      if (f.object >= 0) return period;
    }
  }
  Clock::duration idle = kIdleTick;
  if (state_rate_Hz_ > 0.0) {
    idle = std::min(idle, std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / state_rate_Hz_)));
  }
  return std::max(period, idle);
}

void HapticBridge::FollowControlStates() {
  if (!control_reader_) return;
  msg::ControlState state;
  dds::SampleMeta meta;
  while (control_reader_.TakeNext(state, meta)) {
    if (!meta.valid_data) continue;
    const std::string bad = dds::CheckControlState(state, config_.where.session);
    if (!dropped_.Accept("control_state", "participant " + dds::ParticipantOf(meta.writer), bad, say_)) continue;
    const std::string id = state.control_id().to_string();
    // Another hand's motion (moving, position) is for screens: the haptic loop takes settled
    // states only, and each once.
    const auto known = control_states_.find(id);
    const bool settled_change = known == control_states_.end() || known->second.scene() != state.scene() ||
                                known->second.index() != state.index() || known->second.engaged() != state.engaged();
    if (settled_change && renderer_ && state.scene().to_string() == renderer_->scene().name &&
        !renderer_->SetControlState(id, state.index(), state.engaged())) {
      say_("control state of '" + id + "' not handed to the haptic loop: its queue is full");
    }
    control_states_[id] = state;
  }
}

void HapticBridge::FollowDeskInput() {
  if (desk_ == nullptr || !desk_reader_) return;
  msg::DeskInput input;
  dds::SampleMeta meta;
  bool posted = false;
  DeskTarget target;
  while (desk_reader_.TakeNext(input, meta)) {
    if (!meta.valid_data || input.user().to_string() != config_.user) continue;
    const std::string bad = dds::CheckDeskInput(input, config_.where.session);
    if (!dropped_.Accept("desk_input", "participant " + dds::ParticipantOf(meta.writer), bad, say_)) continue;
    target = ToDeskTarget(input, common::SteadyNowNs());
    posted = true;
  }
  const std::uint64_t now_ns = common::SteadyNowNs();
  if (posted) {
    desk_->Post(target);  // the newest only: the haptic thread smooths towards it
    ++desk_inputs_;
    desk_last_ns_ = now_ns;
    if (target.focused != desk_live_) {
      desk_live_ = target.focused;
      say_(desk_live_ ? Format("desk: the hand is live at (%.3f, %.3f, %.3f) m", target.p_WH_m[0], target.p_WH_m[1],
                               target.p_WH_m[2])
                      : std::string("desk: the view lost focus: the hand is released"));
    }
  } else if (desk_live_ && desk_last_ns_ != 0 &&
             static_cast<double>(now_ns - desk_last_ns_) * 1e-9 > desk_->config().input_timeout_s) {
    desk_live_ = false;
    say_(Format("desk: no input for %.1f s: the hand is released", desk_->config().input_timeout_s));
  }
}

void HapticBridge::Tick() {
  const std::uint64_t start_ns = common::SteadyNowNs();
  if (last_tick_ns_ != 0) tick_interval_.Record(1e-3 * static_cast<double>(start_ns - last_tick_ns_));
  last_tick_ns_ = start_ns;
  ++ticks_;
  // The interval asked for is the one this state of the bridge asks (TickPeriod): an idle bridge
  // at its idle period is on time, not slow.
  const double asked_s = std::chrono::duration<double>(TickPeriod()).count();
  tick_asked_->store(false, std::memory_order_release);
  if (std::string line = overload_.Tick(start_ns, asked_s); !line.empty()) say_(line);
  FollowDeskInput();
  FollowControlStates();
  const std::uint32_t revision = scene_revision_;
  ApplySceneChange();
  // Building a world's models (1.1 s for the dinosaur) is this thread's own work, not a machine
  // without room: the overload watch starts a new window after it.
  if (scene_revision_ != revision) overload_.Restart(common::SteadyNowNs());
  loop_.CollectRetired();
  if (renderer_) {
    ForwardControlEvents();
    TakeReport();
    ReceivePeers(true);
    FollowPeerBodies(true);
    DumpLocalFields();
  }
  PublishDeviceState(false);
  PublishContactSet();
  PublishStatistics();
}

void HapticBridge::Couple() {
  FollowDeskInput();
  if (!renderer_) return;
  if (renderer_->TakeMotion()) PublishDeviceState(true);
  // A touch's end wakes the bridge (the touched object changed): its control event (a button's
  // release) goes now, not at the next tick, which may be an idle one.
  ForwardControlEvents();
  TakeReport();
  ReceivePeers(false);
  FollowPeerBodies(false);
  PublishContactSet();
}

void HapticBridge::WriteCouplingTrace() const {
  if (config_.coupling_trace_file.empty()) return;
  std::ofstream out(config_.coupling_trace_file);
  if (!out) throw std::runtime_error("cannot write coupling trace " + config_.coupling_trace_file);
  for (const CouplingTrace::Row& r : trace_rows_.rows) {
    out << r.kind << ' ' << r.a << ' ' << r.b << ' ' << r.c << ' ' << r.d << '\n';
  }
}

void HapticBridge::ApplySceneChange() {
  msg::SceneState state;
  dds::SampleMeta meta;
  while (scene_reader_.TakeNext(state, meta)) {
    if (!meta.valid_data || state.revision() == scene_revision_) continue;
    const std::string bad = dds::CheckSceneState(state, config_.where.session);
    if (!dropped_.Accept("scene_state", "participant " + dds::ParticipantOf(meta.writer), bad, say_)) continue;
    scene_revision_ = state.revision();
    server_tick_Hz_ = state.tick_Hz();
    try {
      AdoptScene(state);
    } catch (const std::exception& e) {
      // A scene this node cannot build: keep the old one (or none): no forces from it.
      say_(std::string("cannot build scene '") + state.scene().to_string() + "': " + e.what());
    }
  }
}

void HapticBridge::AdoptScene(const msg::SceneState& state) {
  scene::Scene scene = scene::LoadSceneByName(state.scene().to_string());
  const auto& g = state.gravity_W_m_per_s2();
  scene.gravity_W_m_per_s2 = Eigen::Vector3d(g[0], g[1], g[2]);
  if (state.session_epoch_unix_ns() != 0) {
    session_clock_ = common::SessionClock::FromEpoch(state.session_epoch_unix_ns());
  }
  const auto t0 = Clock::now();
  auto next = std::make_shared<SceneRenderer>(scene, models_options_, session_clock_);
  next->SetCouplingPassivity(config_.coupling_passivity);
  if (field_dump_) next->EnableLoadSnapshots();
  const bool same_world = renderer_ && renderer_->scene().name == scene.name;
  if (same_world && have_report_) {
    for (int b = 0; b < report_.num_bodies; ++b) {
      const auto& body = report_.bodies[b];
      const Eigen::Isometry3d X = PoseOf(body);
      next->PlaceBody(renderer_->IdOf(body.object), X);
      say_(Format("  %s stays at (%.3f, %.3f, %.3f) m", renderer_->IdOf(body.object).c_str(), X.translation().x(),
                  X.translation().y(), X.translation().z()));
    }
  }
  if (!same_world) bodies_.clear();
  // Controls where the session left them (a new revision of this world keeps its lever's detent).
  for (const auto& [id, control] : control_states_) {
    if (control.scene().to_string() == scene.name) next->PlaceControl(id, control.index(), control.engaged());
  }
  peers_.Clear();
  deadband_.Reset();
  contact_pacer_.Reset();
  coupling_before_ = coupling_stats();
  coupling_now_ = {};
  if (config_.coupling_on_wake) next->SetWakeup(wake_);
  renderer_ = next;
  have_report_ = false;
  loop_.SetRenderer(renderer_);
  if (const double t_s = loop_.now_s(); device_.OnWorldReady(t_s, scene.name)) {
    say_(Format("hand script starts at loop time %.3f s (the first world is here)", t_s));
  }
  say_(Format("scene '%s' revision %u: %d objects, %zu controls, gravity %.2f m/s^2 (%.2f s)", scene.name.c_str(),
              scene_revision_, renderer_->models().world->num_objects(), scene.controls.size(),
              scene.gravity_W_m_per_s2.z(), std::chrono::duration<double>(Clock::now() - t0).count()));
}

void HapticBridge::ForwardControlEvents() {
  controls::ControlEvent event;
  while (renderer_->TakeEvent(event)) {
    held_events_.push_back(session::ToMessage(event, config_.where.session, config_.user, common::SteadyNowNs()));
    if (held_events_.size() > kMaxHeldEvents) {
      held_events_.pop_front();
      if (held_events_dropped_++ == 0) say_("control events wait for the world server's reader; the oldest are dropped");
    }
    if (event.kind == controls::EventKind::kMoving) continue;  // up to 25 a second: not logged
    say_(Format("control %s: %s (value %.3f, error %.1f mm)", std::string(event.id()).c_str(),
                controls::ToString(event.kind), event.value, 1e3 * event.error_m));
  }
  // Written once a reader (the world server's) has matched this writer: before, they are lost.
  if (held_events_.empty() || event_writer_.matched_readers() == 0) return;
  for (const msg::ControlEvent& m : held_events_) {
    event_writer_.Write(m);
    ++control_events_sent_;
  }
  held_events_.clear();
}

void HapticBridge::ReceivePeers(bool tick) {
  names_.Follow(member_reader_);
  // A peer touching something sends its contact set at its publish rate; one silent for
  // longer has gone (or stopped touching without a last sample): its contacts fade out.
  const auto now = Clock::now();
  const std::uint64_t now_ns = common::SteadyNowNs();
  msg::ContactSet peer;
  dds::SampleMeta meta;
  bool taken = false;
  while (contact_reader_.TakeNext(peer, meta)) {
    if (!meta.valid_data || peer.user().to_string() == config_.user) continue;
    std::string bad = dds::CheckContactSet(peer, config_.where.session);
    // A present peer's name from another participant: forged (or a stale participant of a
    // peer that rejoined, until its old member is gone).
    if (bad.empty()) bad = names_.Check(peer.user().to_string(), meta.writer);
    if (dropped_.Accept("contact_set", peer.user().to_string(), bad, say_)) {
      if (peers_heard_.insert(peer.user().to_string()).second) {
        say_("first contact set from peer '" + peer.user().to_string() + "'");
      }
      peers_.Receive(peer, now, config_.user);
      // The sender's write to this take, on the steady clock both share on one host (the
      // DDS hop and this bridge's wake-up, or its tick with coupling_on_wake off).
      if (peer.stamp_ns() <= now_ns) peer_age_.Record(1e-3 * static_cast<double>(now_ns - peer.stamp_ns()));
      newest_peer_stamp_ns_ = std::max(newest_peer_stamp_ns_, peer.stamp_ns());
      if (!config_.coupling_trace_file.empty()) trace_rows_.Add({'t', peer.stamp_ns(), now_ns, 0, 0});
      taken = true;
    }
  }
  // Between ticks only a new set is handed over; a tick also lets the silent ones expire.
  if (!tick && !taken) return;
  peers_.Expire(now);
  RemoteContacts remote = ToRemoteContacts(peers_, renderer_->models(), now);
  remote.newest_stamp_ns = newest_peer_stamp_ns_;
  renderer_->SetRemote(remote);
  renderer_->TakeCouplingStats(coupling_now_);
}

contact::CouplingPassivityStats HapticBridge::coupling_stats() const {
  contact::CouplingPassivityStats s = coupling_before_;
  const contact::CouplingPassivityStats& n = coupling_now_;
  s.steps += n.steps;
  s.held_back += n.held_back;
  s.energy_sent_J += n.energy_sent_J;
  s.energy_received_J += n.energy_received_J;
  s.observer_min_J = std::min(s.observer_min_J, n.observer_min_J);
  s.drift_max_m = std::max(s.drift_max_m, n.drift_max_m);
  s.energy_granted_J += n.energy_granted_J;
  s.granted_still += n.granted_still;
  s.channels_total += n.channels_total;
  return s;
}

void HapticBridge::DumpLocalFields() {
  if (!field_dump_) return;
  try {
    field_dump_->Update(*renderer_);
  } catch (const std::exception& e) {
    say_(std::string(e.what()) + "; no more field dumps");  // the touch goes on
    field_dump_.reset();
  }
}

void HapticBridge::TakeReport() {
  if (!renderer_->TakeReport(report_)) return;
  have_report_ = true;
  // The sender's write to the haptic step that first used the set (same host: one clock).
  if (report_.peer_stamp_ns == 0 || report_.peer_stamp_ns == last_loop_peer_stamp_ns_) return;
  last_loop_peer_stamp_ns_ = report_.peer_stamp_ns;
  if (report_.peer_seen_ns >= report_.peer_stamp_ns) {
    peer_loop_age_.Record(1e-3 * static_cast<double>(report_.peer_seen_ns - report_.peer_stamp_ns));
  }
  if (!config_.coupling_trace_file.empty()) trace_rows_.Add({'u', report_.peer_stamp_ns, report_.peer_seen_ns, 0, 0});
}

void HapticBridge::FollowPeerBodies(bool tick) {
  // The owner simulates a grasped body, the world server a free one; this hand follows every
  // body it does not own itself.
  msg::ObjectState body;
  dds::SampleMeta meta;
  bool taken = false;
  while (object_reader_.TakeNext(body, meta)) {
    if (!meta.valid_data) continue;
    const std::string bad = dds::CheckObjectState(body, config_.where.session);
    if (!dropped_.Accept("object_state", body.owner().to_string(), bad, say_)) continue;
    bodies_[body.object_id().to_string()] = {body, common::SteadyNowNs()};
    taken = true;
  }
  // Between ticks: a new state (a hand-over, a thrown body) goes to the loop at once; a hand
  // that owns a body or holds one for a hand-over follows its own report at once too.
  if (!tick && !taken && owned_ < 0 && hand_over_.held() < 0) return;
  const world::SceneModels& models = renderer_->models();
  FollowedBodies followed = ToFollowedBodies(bodies_, config_.user, models);
  // A body this hand lets go of while another user's hand grasps it stays still there until
  // the server's hand-over arrives (HandOverHold).
  owned_ = OwnedBody(bodies_, config_.user, models);
  const std::int32_t held = have_report_ ? owned_ : -1;
  const std::string grasper =
      held >= 0 ? PeerGrasping(peers_, models.ids[static_cast<std::size_t>(held)], Clock::now()) : std::string();
  if (hand_over_.Update(held, report_, grasper, common::SteadyNowNs(), followed)) {
    say_("let go of '" + models.ids[static_cast<std::size_t>(held)] + "' while '" + grasper +
         "' grasps it: held still there until the hand-over");
  }
  renderer_->SetFollowed(followed);
}

void HapticBridge::PublishDeviceState(bool moved) {
  HapticSnapshot snapshot;
  if (!loop_.TakeSnapshot(snapshot)) return;
  ToDeviceState(snapshot, state_msg_);
  // Skip what nobody needs: no viewer matched, nothing sent (the trace still records); with
  // viewers, no faster than the fastest of them draws.
  const int readers = state_writer_.matched_readers();
  const dds::Viewers viewers = names_.viewers();
  const double rate_Hz = config_.paced_streams
                             ? session::DeviceStateRate(readers, viewers.count, viewers.fastest_Hz, config_.publish_Hz)
                             : (readers > 0 ? config_.publish_Hz : 0.0);
  state_rate_Hz_ = rate_Hz;
  // A hand that moves: its state leaves on the haptic step's wake-up (the step posts it at most
  // once a period), and the paced sends pause while it moves (until one and a half periods
  // after the last such send), so the rate stays the viewers'. A hand at rest: at the ticks,
  // paced (docs/devices.md, "Motion to photon").
  const std::uint64_t now_ns = common::SteadyNowNs();
  const std::uint64_t period_ns = rate_Hz > 0.0 ? static_cast<std::uint64_t>(1e9 / rate_Hz) : 0;
  if (renderer_ && config_.coupling_on_wake) renderer_->SetMotionWake(rate_Hz > 0.0 ? kMotionWake_m : 0.0, period_ns);
  bool send = false;
  if (moved) {
    send = rate_Hz > 0.0;
    if (send) moved_sent_ns_ = now_ns;
  } else {
    send = state_pacer_.Due(now_ns, rate_Hz) && now_ns >= moved_sent_ns_ + period_ns + period_ns / 2;
  }
  if (send) {
    state_writer_.Write(state_msg_);
    ++device_states_published_;
    if (moved) ++device_states_on_motion_;
  }
  if (trace_ != nullptr) WriteTraceRow(*trace_, snapshot);
}

void HapticBridge::PublishContactSet() {
  if (!renderer_ || !have_report_) return;
  const bool active =
      ToContactSet(report_, renderer_->models(), owned_, models_options_.fingertip_radius_m, contacts_msg_);
  const std::uint64_t now_ns = common::SteadyNowNs();
  if (!(active || last_sent_active_) || contact_writer_.matched_readers() == 0) {
    last_sent_active_ = active;
    renderer_->SetReportWake(false);
    return;
  }
  // While a peer's loop solves an object with this hand's contacts, every report goes to the
  // deadband as soon as the haptic step made it (the step posts the wake-up); else the world
  // server, reading at its tick, is the only reader: no faster than that tick. A set that is
  // not due is left for the next due one (the end of a touch included: last_sent_active_
  // keeps it owed).
  const bool shared = session::SharesObjectWithPeer(contacts_msg_, peers_, Clock::now());
  const bool on_wake = config_.coupling_on_wake && shared;
  renderer_->SetReportWake(on_wake);
  const double rate_Hz =
      config_.paced_streams ? session::ContactSetRate(shared, server_tick_Hz_, config_.publish_Hz) : config_.publish_Hz;
  if (!on_wake && !contact_pacer_.Due(now_ns, rate_Hz)) return;
  if (deadband_.Offer(contacts_msg_, now_ns)) {
    contacts_msg_.stamp_ns(now_ns);
    contacts_msg_.seq(contacts_msg_.seq() + 1);
    contact_writer_.Write(contacts_msg_);
    // What went, for the haptic step to judge its next reports by: a held press then wakes
    // this thread when the deadband may send, not after every step.
    renderer_->SetSentReference(ToSentReference(report_, contacts_msg_, owned_, deadband_.config(), now_ns));
    if (!config_.coupling_trace_file.empty()) {
      trace_rows_.Add({'w', contacts_msg_.seq(), report_.step_ns, now_ns, common::SteadyNowNs()});
    }
    ++contact_sets_sent_;
    if (shared) ++contact_sets_shared_;
    if (report_.step_ns != 0 && report_.step_ns <= contacts_msg_.stamp_ns()) {
      report_age_.Record(1e-3 * static_cast<double>(contacts_msg_.stamp_ns() - report_.step_ns));
    }
  }
  last_sent_active_ = active;
}

void HapticBridge::PublishStatistics() {
  if (Clock::now() < next_stats_) return;
  next_stats_ += std::chrono::seconds(1);
  common::LoopStats stats;
  if (loop_.TakeStats(stats) && stats_writer_.matched_readers() > 0) {
    ToLoopStatistics(stats, loop_.faults(), stats_msg_);
    stats_msg_.samples_dropped(dropped_.total());
    stats_traffic_.Fill(stats_msg_);
    stats_writer_.Write(stats_msg_);
  }
}

}  // namespace handshare::haptic
