#include "session_publisher.hpp"

#include "handshare/common/clock.hpp"
#include "server_conversions.hpp"

namespace handshare::server {

SessionPublisher::SessionPublisher(dds::Participant& participant, std::string session)
    : session_(std::move(session)),
      scene_writer_(dds::MakeWriter<msg::SceneState>(participant, dds::topics::kSceneState)),
      board_writer_(dds::MakeWriter<msg::MessageBoard>(participant, dds::topics::kMessageBoard)),
      control_state_writer_(dds::MakeWriter<msg::ControlState>(participant, dds::topics::kControlState)),
      object_writer_(dds::MakeWriter<msg::ObjectState>(participant, dds::topics::kObjectState)),
      deformation_writer_(dds::MakeWriter<msg::Deformation>(participant, dds::topics::kDeformation)),
      roster_writer_(dds::MakeWriter<msg::SessionRoster>(participant, dds::topics::kSessionRoster)) {}

void SessionPublisher::Take(std::span<const SessionEvent> events, Clock::time_point /*now*/) {
  const auto write = Overloaded{
      [&](const SceneRevised& e) {
        scene_writer_.Write(ToSceneState(e.scene, session_, e.revision, e.epoch_unix_ns, e.tick_Hz));
      },
      // Transient-local: a node that hears this server but never one of these members can tell,
      // and join again.
      [&](const RosterChanged& e) { roster_writer_.Write(ToSessionRoster(e.member_ids, session_)); },
      // Every language under one number (each screen and guide shows its own); transient-local
      // keeps the newest for late joiners.
      [&](const MessageSaid& e) {
        for (const auto& m : e.messages) board_writer_.Write(ToMessageBoard(m, session_, e.message_id));
      },
      [&](const ControlStateChanged& e) { control_state_writer_.Write(ToControlState(e.record, session_)); },
      [&](const BodyMoved& e) { object_writer_.Write(ToObjectState(e.body, session_, common::SteadyNowNs())); },
      [&](const FieldChanged& e) {
        deformation_writer_.Write(ToDeformation(e.object_id, session_, e.sample));
        ++deformations_sent_;
      },
      [](const auto&) {},
  };
  for (const SessionEvent& event : events) std::visit(write, event);
}

}  // namespace handshare::server
