#include "server_session.hpp"

#include <algorithm>

#include "server_conversions.hpp"
#include "handshare/common/clock.hpp"
#include "handshare/dds/membership.hpp"
#include "handshare/world_server/control_actions.hpp"

namespace handshare::server {

namespace {
ObjectAuthorityOptions AuthorityOptions(const WorldServerConfig& config) {
  ObjectAuthorityOptions options;
  if (!config.cache_dir.empty()) options.models.cache_dir = config.cache_dir;
  options.dump_dir = config.dump_dir;
  options.delta.threshold_m = config.deformation_threshold_m;
  return options;
}
}  // namespace

namespace {
// The scene a resume point describes (its world, with the gravity and title it had then).
scene::Scene ResumedScene(scene::Scene fallback, const ResumePoint* resume) {
  if (resume == nullptr) return fallback;
  scene::Scene s = scene::LoadSceneByName(resume->state.scene);
  const auto& g = resume->state.gravity_W_m_per_s2;
  s.gravity_W_m_per_s2 = Eigen::Vector3d(g[0], g[1], g[2]);
  s.title = resume->state.title;
  return s;
}
}  // namespace

ServerSession::ServerSession(WorldServer& server, const WorldServerConfig& config, dds::Participant& participant,
                             scene::Scene scene, const ResumePoint* resume)
    : server_(server),
      session_(config.where.session),
      tick_Hz_(config.tick_Hz),
      clock_(resume ? common::SessionClock::FromEpoch(resume->state.epoch_unix_ns) : common::SessionClock()),
      scene_(ResumedScene(std::move(scene), resume)),
      objects_(config.where.session, AuthorityOptions(config), clock_),
      scene_writer_(dds::MakeWriter<msg::SceneState>(participant, dds::topics::kSceneState)),
      board_writer_(dds::MakeWriter<msg::MessageBoard>(participant, dds::topics::kMessageBoard)),
      control_state_writer_(dds::MakeWriter<msg::ControlState>(participant, dds::topics::kControlState)),
      object_writer_(dds::MakeWriter<msg::ObjectState>(participant, dds::topics::kObjectState)),
      deformation_writer_(dds::MakeWriter<msg::Deformation>(participant, dds::topics::kDeformation)),
      roster_writer_(dds::MakeWriter<msg::SessionRoster>(participant, dds::topics::kSessionRoster)),
      member_reader_(dds::MakeReader<msg::MemberInfo>(participant, dds::topics::kMemberInfo)),
      contact_reader_(dds::MakeReader<msg::ContactSet>(participant, dds::topics::kContactSet)),
      control_reader_(dds::MakeReader<msg::ControlEvent>(participant, dds::topics::kControlEvent)) {
  if (resume != nullptr) {
    // The same revision and message number again: nodes that have them change nothing.
    revision_ = resume->state.revision - 1;
    message_id_ = resume->state.message_id - 1;
    for (const auto& p : resume->poses) {
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      X.linear() = Eigen::Quaterniond(p.q_WO_wxyz[0], p.q_WO_wxyz[1], p.q_WO_wxyz[2], p.q_WO_wxyz[3])
                       .normalized()
                       .toRotationMatrix();
      X.translation() = Eigen::Vector3d(p.p_WO_m[0], p.p_WO_m[1], p.p_WO_m[2]);
      // A body its owner held: kept for that owner's claim for 2 s (a participant lease of 1 s
      // and rediscovery, 0.3 s measured), so it is not dropped and re-grabbed.
      objects_.PlaceBody(p.object_id, X, p.owner, std::chrono::seconds(2));
    }
  }
  PublishScene();
  PublishRoster();
  server_.Say("session '" + session_ + "' on domain " + std::to_string(config.where.domain_id) + ": scene '" +
              scene_.name + "' (" + std::to_string(scene_.objects.size()) + " objects)");
  server_.OnSceneChange(scene_.name, scene_.title);
  objects_.SetScene(scene_);
  ResetControlStates(resume);
  ShowMessage(resume != nullptr && !resume->state.board.empty() ? resume->state.board : scene_.messages);
}

void ServerSession::Tick(Clock::time_point now, double dt_s) {
  TakeMembers(now);
  TakeControlEvents();
  TakeContactSets(now);
  StepObjects(now, dt_s);
}

void ServerSession::TakeMembers(Clock::time_point now) {
  std::vector<MemberEvent> events;
  msg::MemberInfo info;
  dds::SampleMeta meta;
  while (member_reader_.TakeNext(info, meta)) {
    std::optional<MemberEvent> event;
    if (meta.valid_data && info.leaving()) {
      event = members_.OnGone(meta.instance, /*disposed=*/true);  // a clean leave, said in data
    } else if (meta.valid_data && meta.instance_state == dds::InstanceState::kAlive) {
      if (!Accepted("member_info", info.user().to_string(), dds::CheckMemberInfo(info, session_))) continue;
      if (const std::string other = members_.CheckAuthor(info.user().to_string(), meta.writer); !other.empty()) {
        // The newest announcement names the user's participant (a restarted node's must win
        // before the old one's lease runs out); say so, for a station that takes a name.
        server_.Say("member " + info.user().to_string() + " announced again by another participant (" + other +
                    "): samples in this name are taken from the new one");
      }
      event = members_.OnInfo(meta.instance, meta.writer, ToMember(info));
    } else if (meta.instance_state != dds::InstanceState::kAlive) {
      event = members_.OnGone(meta.instance, meta.instance_state == dds::InstanceState::kDisposed);
    }
    if (event) events.push_back(*event);
  }
  // Writers that vanished without disposing (killed processes, lost hosts), and writers back
  // after a partition healed: their members rejoin, once each.
  dds::WriterChange change;
  while (member_reader_.TakeWriterChange(change)) {
    for (auto& e : change.alive ? members_.OnWriterRegained(change.writer) : members_.OnWriterLost(change.writer)) {
      events.push_back(e);
    }
  }
  if (!events.empty()) PublishRoster();
  for (const auto& event : events) {
    server_.OnMemberEvent(event, members_.present().size());
    if (event.change != MemberChange::kJoined) {
      objects_.OnUserGone(event.member.user, now);
    } else if (event.member.kind == dds::ToString(msg::NODE_GRAPHICS)) {
      objects_.RequestKeyframes();  // a new spectator gets the whole deformed surfaces
    }
  }
}

void ServerSession::PublishRoster() {
  msg::SessionRoster roster;
  roster.session(session_);
  for (const Member& m : members_.present()) {
    if (roster.members().size() == kMaxRoster) break;  // IDL bound; a session has far fewer
    roster.members().push_back(m.member_id);
  }
  roster_writer_.Write(roster);
}

void ServerSession::TakeControlEvents() {
  msg::ControlEvent sample;
  dds::SampleMeta meta;
  bool applied = false;
  while (control_reader_.TakeNext(sample, meta)) {
    if (!meta.valid_data) continue;
    const std::string user = sample.user().to_string();
    if (!Accepted("control_event", user, dds::CheckControlEvent(sample, session_)) ||
        !Accepted("control_event", user, members_.CheckAuthor(user, meta.writer))) {
      continue;
    }
    const auto input = ToControlInput(sample);
    if (!input) continue;  // CheckControlEvent refused every kind ToControlInput cannot map
    if (input->kind == controls::EventKind::kMoving) {
      // Motion (up to 25 a second while a hand moves a control): for the screens, not the log.
      if (const ControlStateRecord* changed = UpdateControlState(control_states_, *input)) {
        control_state_writer_.Write(ToControlState(*changed, session_));
      }
      continue;
    }
    server_.OnControlEvent(ToControlRecord(sample, *input, common::UnixNowNs()));
    // Where the event left its control, before its action (which may leave the world).
    if (const ControlStateRecord* changed = UpdateControlState(control_states_, *input)) {
      control_state_writer_.Write(ToControlState(*changed, session_));
      LogControlPlace(*changed);
    }
    const ControlOutcome outcome = ApplyControlAction(scene_, *input, LoadWorld);
    if (outcome.world_changed) {
      ResetControlStates();
      pose_logged_.clear();
      if (SessionLog* log = server_.session_log()) log->ForgetObjectPoses();
    }
    if (outcome.world_changed || outcome.gravity_changed) objects_.SetScene(scene_);
    if (outcome.revised) PublishScene();
    for (const auto& note : outcome.notes) {
      server_.Say(outcome.revised ? note + " (revision " + std::to_string(revision_) + ")" : note);
    }
    if (outcome.revised) server_.OnSceneChange(scene_.name, scene_.title);
    for (const auto& board : outcome.boards) ShowMessage(board);
    applied = true;
  }
  // A control event and what it did are committed before the tick goes on (a few a minute):
  // a server killed right after still leaves them in the log, and a restart resumes from them.
  if (applied) server_.CommitLog();
}

void ServerSession::TakeContactSets(Clock::time_point now) {
  msg::ContactSet set;
  dds::SampleMeta meta;
  while (contact_reader_.TakeNext(set, meta)) {
    if (!meta.valid_data) continue;
    const std::string user = set.user().to_string();
    if (Accepted("contact_set", user, dds::CheckContactSet(set, session_)) &&
        Accepted("contact_set", user, members_.CheckAuthor(user, meta.writer))) {
      objects_.OnContactSet(set, now);
    }
  }
}

void ServerSession::StepObjects(Clock::time_point now, double dt_s) {
  TickOutput out = objects_.Tick(now, dt_s);
  for (const auto& note : out.notes) server_.Say(note);
  for (const auto& change : out.ownership) server_.OnOwnershipChange(change);
  for (const auto& state : out.states) object_writer_.Write(state);
  LogPoses(out.states, now);
  TracePoses(out.states);
  for (const auto& [object_id, sample] : out.deformations) {
    deformation_writer_.Write(ToDeformation(object_id, session_, sample));
    ++deformations_sent_;
  }
}

void ServerSession::ResetControlStates(const ResumePoint* resume) {
  control_states_ = InitialControlStates(scene_, /*known=*/resume == nullptr);
  if (resume != nullptr) {
    for (const ControlPlace& place : resume->controls) {
      if (place.scene != scene_.name) continue;
      // A place the control cannot have (the scene file changed since, or the log was edited)
      // leaves it unknown, as a log without places does.
      const auto spec = std::find_if(scene_.controls.begin(), scene_.controls.end(),
                                     [&](const scene::ControlSpec& c) { return c.id == place.control_id; });
      if (spec == scene_.controls.end()) continue;
      if (!IndexFits(*spec, place.index)) {
        server_.Say("control '" + place.control_id + "': the session log places it at index " +
                    std::to_string(place.index) + ", which it does not have: left where the nodes have it");
        continue;
      }
      for (ControlStateRecord& r : control_states_) {
        if (r.control_id != place.control_id) continue;
        r.index = place.index;
        r.engaged = place.engaged;
        r.user = place.user;
        r.changes = place.changes;
        r.known = true;
      }
    }
  } else if (SessionLog* log = server_.session_log()) {
    log->ForgetControlPlaces();  // the last world's
  }
  for (const auto& r : control_states_) {
    if (!r.known) continue;
    control_state_writer_.Write(ToControlState(r, session_));
    LogControlPlace(r);
  }
}

void ServerSession::LogControlPlace(const ControlStateRecord& record) {
  SessionLog* log = server_.session_log();
  if (log == nullptr || !record.known) return;
  ControlPlace p;
  p.control_id = record.control_id;
  p.scene = record.scene;
  p.unix_ns = common::UnixNowNs();
  p.index = record.index;
  p.engaged = record.engaged;
  p.user = record.user;
  p.changes = record.changes;
  log->OnControlPlace(p);
}

void ServerSession::PublishScene() {
  scene_writer_.Write(ToSceneState(scene_, session_, ++revision_, clock_.EpochUnixNs(), tick_Hz_));
  LogState();
}

void ServerSession::ShowMessage(const std::vector<scene::Message>& messages) {
  if (messages.empty()) return;
  // Every language of the message, under one number: each screen and guide shows its own.
  ++message_id_;
  for (const auto& m : messages) board_writer_.Write(ToMessageBoard(m, session_, message_id_));
  board_ = messages;
  const auto en = std::find_if(messages.begin(), messages.end(), [](const auto& m) { return m.language == "en"; });
  server_.Say("message board #" + std::to_string(message_id_) + ": " + (en != messages.end() ? en->text : messages[0].text));
  LogState();
}

void ServerSession::LogState() {
  SessionLog* log = server_.session_log();
  if (log == nullptr) return;
  SessionState st;
  st.unix_ns = common::UnixNowNs();
  st.scene = scene_.name;
  st.title = scene_.title;
  st.revision = revision_;
  for (int k = 0; k < 3; ++k) st.gravity_W_m_per_s2[k] = scene_.gravity_W_m_per_s2[k];
  st.epoch_unix_ns = clock_.EpochUnixNs();
  st.message_id = message_id_;
  st.board = board_;
  log->OnState(st);
}

void ServerSession::TracePoses(const std::vector<msg::ObjectState>& states) {
  std::ostream* trace = server_.pose_trace();
  if (trace == nullptr || states.empty()) return;
  const std::uint64_t stamp_ns = common::SteadyNowNs();
  for (const auto& s : states) {
    *trace << stamp_ns << ',' << s.object_id().to_string() << ',' << s.owner().to_string();
    for (int k = 0; k < 3; ++k) *trace << ',' << s.p_WO_m()[k];
    for (int k = 0; k < 3; ++k) *trace << ',' << s.v_WO_m_per_s()[k];
    *trace << '\n';
  }
  trace->flush();  // a test follows the file while the server runs
}

void ServerSession::LogPoses(const std::vector<msg::ObjectState>& states, Clock::time_point now) {
  SessionLog* log = server_.session_log();
  if (log == nullptr) return;
  for (const auto& s : states) {
    auto& last = pose_logged_[s.object_id().to_string()];
    if (now - last < kPoseLogPeriod) continue;
    last = now;
    ObjectPose p;
    p.object_id = s.object_id().to_string();
    p.owner = s.owner().to_string();
    p.unix_ns = common::UnixNowNs();
    for (int k = 0; k < 3; ++k) p.p_WO_m[k] = s.p_WO_m()[k];
    for (int k = 0; k < 4; ++k) p.q_WO_wxyz[k] = s.q_WO_wxyz()[k];
    log->OnObjectPose(p);
  }
}

}  // namespace handshare::server
