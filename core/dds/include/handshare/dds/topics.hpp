#pragma once
/// Topic names and the QoS profile each one uses (profiles in deploy/qos/handshare_qos.xml).
/// One table, so every node writes and reads a topic with matching QoS.
namespace handshare::dds::topics {

struct TopicSpec {
  const char* name;
  const char* writer_profile;
  const char* reader_profile;
};

inline constexpr TopicSpec kMemberInfo{"handshare/member_info", "member_writer", "member_reader"};
inline constexpr TopicSpec kSceneState{"handshare/scene_state", "state_writer", "state_reader"};
inline constexpr TopicSpec kDeviceState{"handshare/device_state", "device_writer", "device_reader"};
inline constexpr TopicSpec kContactSet{"handshare/contact_set", "stream_writer", "stream_reader"};
inline constexpr TopicSpec kDeformation{"handshare/deformation", "bulk_writer", "bulk_reader"};
inline constexpr TopicSpec kObjectState{"handshare/object_state", "stream_writer", "stream_reader"};
inline constexpr TopicSpec kControlEvent{"handshare/control_event", "event_writer", "event_reader"};
inline constexpr TopicSpec kVisitAnswers{"handshare/visit_answers", "event_writer", "event_reader"};
inline constexpr TopicSpec kOperatorCommand{"handshare/operator_command", "event_writer", "event_reader"};
inline constexpr TopicSpec kControlState{"handshare/control_state", "state_writer", "state_reader"};
inline constexpr TopicSpec kSessionRoster{"handshare/session_roster", "state_writer", "state_reader"};
inline constexpr TopicSpec kMessageBoard{"handshare/message_board", "state_writer", "state_reader"};
inline constexpr TopicSpec kDeskInput{"handshare/desk_input", "stream_writer", "stream_reader"};
inline constexpr TopicSpec kLoopStatistics{"handshare/loop_statistics", "stream_writer",
                                           "stream_reader"};

}  // namespace handshare::dds::topics
