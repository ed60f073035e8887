#include "server_session.hpp"

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

ServerSession::ServerSession(WorldServer& server, const WorldServerConfig& config, dds::Participant& participant,
                             scene::Scene scene)
    : server_(server),
      session_(config.where.session),
      scene_(std::move(scene)),
      objects_(config.where.session, AuthorityOptions(config), clock_),
      scene_writer_(dds::MakeWriter<msg::SceneState>(participant, dds::topics::kSceneState)),
      board_writer_(dds::MakeWriter<msg::MessageBoard>(participant, dds::topics::kMessageBoard)),
      object_writer_(dds::MakeWriter<msg::ObjectState>(participant, dds::topics::kObjectState)),
      deformation_writer_(dds::MakeWriter<msg::Deformation>(participant, dds::topics::kDeformation)),
      member_reader_(dds::MakeReader<msg::MemberInfo>(participant, dds::topics::kMemberInfo)),
      contact_reader_(dds::MakeReader<msg::ContactSet>(participant, dds::topics::kContactSet)),
      control_reader_(dds::MakeReader<msg::ControlEvent>(participant, dds::topics::kControlEvent)) {
  PublishScene();
  server_.Say("session '" + session_ + "' on domain " + std::to_string(config.where.domain_id) + ": scene '" +
              scene_.name + "' (" + std::to_string(scene_.objects.size()) + " objects)");
  server_.OnSceneChange(scene_.name, scene_.title);
  objects_.SetScene(scene_);
  ShowMessage(scene_.messages);
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
    if (meta.valid_data && meta.instance_state == dds::InstanceState::kAlive) {
      if (!Accept("member_info", info.user().to_string(), dds::CheckMemberInfo(info, session_))) continue;
      event = members_.OnInfo(meta.instance, meta.writer, ToMember(info));
    } else if (meta.instance_state != dds::InstanceState::kAlive) {
      event = members_.OnGone(meta.instance, meta.instance_state == dds::InstanceState::kDisposed);
    }
    if (event) events.push_back(*event);
  }
  // Writers that vanished without disposing: killed processes, lost hosts.
  dds::SampleMeta::Key lost_writer;
  while (member_reader_.TakeLostWriter(lost_writer)) {
    for (auto& e : members_.OnWriterLost(lost_writer)) events.push_back(e);
  }
  for (const auto& event : events) {
    server_.OnMemberEvent(event, members_.present().size());
    if (event.change != MemberChange::kJoined) {
      objects_.OnUserGone(event.member.user, now);
    } else if (event.member.kind == dds::ToString(msg::NODE_GRAPHICS)) {
      objects_.RequestKeyframes();  // a new spectator gets the whole deformed surfaces
    }
  }
}

void ServerSession::TakeControlEvents() {
  msg::ControlEvent sample;
  dds::SampleMeta meta;
  while (control_reader_.TakeNext(sample, meta)) {
    if (!meta.valid_data) continue;
    if (!Accept("control_event", sample.user().to_string(), dds::CheckControlEvent(sample, session_))) continue;
    const auto input = ToControlInput(sample);
    if (!input) continue;  // CheckControlEvent refused every kind ToControlInput cannot map
    server_.OnControlEvent(ToControlRecord(sample, *input, common::UnixNowNs()));
    const ControlOutcome outcome = ApplyControlAction(scene_, *input, LoadWorld);
    if (outcome.world_changed || outcome.gravity_changed) objects_.SetScene(scene_);
    if (outcome.revised) PublishScene();
    for (const auto& note : outcome.notes) {
      server_.Say(outcome.revised ? note + " (revision " + std::to_string(revision_) + ")" : note);
    }
    if (outcome.revised) server_.OnSceneChange(scene_.name, scene_.title);
    for (const auto& board : outcome.boards) ShowMessage(board);
  }
}

void ServerSession::TakeContactSets(Clock::time_point now) {
  msg::ContactSet set;
  dds::SampleMeta meta;
  while (contact_reader_.TakeNext(set, meta)) {
    if (!meta.valid_data) continue;
    if (Accept("contact_set", set.user().to_string(), dds::CheckContactSet(set, session_))) {
      objects_.OnContactSet(set, now);
    }
  }
}

void ServerSession::StepObjects(Clock::time_point now, double dt_s) {
  TickOutput out = objects_.Tick(now, dt_s);
  for (const auto& note : out.notes) server_.Say(note);
  for (const auto& change : out.ownership) server_.OnOwnershipChange(change);
  for (const auto& state : out.states) object_writer_.Write(state);
  for (const auto& [object_id, sample] : out.deformations) {
    deformation_writer_.Write(ToDeformation(object_id, session_, sample));
    ++deformations_sent_;
  }
}

bool ServerSession::Accept(std::string_view topic, std::string_view sender, const std::string& reason) {
  if (reason.empty()) return true;
  if (const std::string line = dropped_.Count(topic, sender, reason); !line.empty()) server_.Say(line);
  return false;
}

void ServerSession::PublishScene() {
  scene_writer_.Write(ToSceneState(scene_, session_, ++revision_, clock_.EpochUnixNs()));
}

void ServerSession::ShowMessage(const std::vector<scene::Message>& messages) {
  for (const auto& m : messages) {
    if (m.language != "en") continue;
    board_writer_.Write(ToMessageBoard(m, session_, ++message_id_));
    server_.Say("message board #" + std::to_string(message_id_) + ": " + m.text);
    return;
  }
}

}  // namespace handshare::server
