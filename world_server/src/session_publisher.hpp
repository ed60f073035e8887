#pragma once
/// The consumer of the session's events that writes the DDS samples: the scene state, the
/// roster, the board, the control states, the rigid bodies' states and the deformations
/// (the conversions are server_conversions.hpp's). The only place the session's outputs
/// become samples. Private to the server library.
#include <cstdint>
#include <string>

#include "handshare/dds/messages.hpp"
#include "handshare/world_server/session_events.hpp"

namespace handshare::server {

class SessionPublisher : public SessionEventSink {
 public:
  SessionPublisher(dds::Participant& participant, std::string session);

  void Take(std::span<const SessionEvent> events, Clock::time_point now) override;

  std::uint64_t deformations_sent() const { return deformations_sent_; }

 private:
  std::string session_;
  dds::Writer<msg::SceneState> scene_writer_;
  dds::Writer<msg::MessageBoard> board_writer_;
  dds::Writer<msg::ControlState> control_state_writer_;
  dds::Writer<msg::ObjectState> object_writer_;
  dds::Writer<msg::Deformation> deformation_writer_;
  dds::Writer<msg::SessionRoster> roster_writer_;
  std::uint64_t deformations_sent_ = 0;
};

}  // namespace handshare::server
