#pragma once
// For tests that put two participants in one process and lose chosen datagrams with Fast DDS's
// test transport (test_UDPv4TransportDescriptor::messages_filter_): the participants' QoS, and
// the DATA submessages of an RTPS message as that filter sees it (the wire format of RTPS 2.x,
// section 8.3). Header only: some helpers that use it are built without the DDS layer.
#include <cstdint>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>
#include <fastdds/rtps/common/CDRMessage_t.h>
#include <fastdds/rtps/transport/TransportDescriptorInterface.h>
#include <fastrtps/xmlparser/XMLProfileManager.h>
#include <memory>
#include <utility>

namespace handshare::dds::test_support {

/// A participant QoS with `transport` as its only transport (no builtin UDP or shared memory).
inline eprosima::fastdds::dds::DomainParticipantQos OnlyOver(
    std::shared_ptr<eprosima::fastdds::rtps::TransportDescriptorInterface> transport) {
  eprosima::fastdds::dds::DomainParticipantQos qos = eprosima::fastdds::dds::PARTICIPANT_QOS_DEFAULT;
  qos.transport().use_builtin_transports = false;
  qos.transport().user_transports.push_back(std::move(transport));
  return qos;
}

/// Turns Fast DDS's intraprocess delivery off: participants of this process then talk over
/// their transports, as two processes would. Call before creating them.
inline void TalkOverTransports() {
  eprosima::fastrtps::LibrarySettingsAttributes library;
  library.intraprocess_delivery = eprosima::fastrtps::INTRAPROCESS_OFF;
  eprosima::fastrtps::xmlparser::XMLProfileManager::library_settings(library);
}

/// One DATA submessage: the writer's entity id (4 octets, the last its kind) and the sample's
/// sequence number.
struct DataSubmessage {
  const eprosima::fastrtps::rtps::octet* writer_id = nullptr;
  std::uint64_t sequence = 0;
};

/// True if `pred` holds for a DATA submessage of `msg` (walked in order; stops at the first).
template <class Pred>
bool AnyData(const eprosima::fastrtps::rtps::CDRMessage_t& msg, Pred pred) {
  constexpr std::uint32_t kHeader = 20;  // "RTPS", version, vendor, GUID prefix
  if (msg.length < kHeader || msg.buffer[0] != 'R' || msg.buffer[1] != 'T') return false;
  std::uint32_t pos = kHeader;
  while (pos + 4 <= msg.length) {
    const std::uint8_t id = msg.buffer[pos];
    const bool little = (msg.buffer[pos + 1] & 0x01) != 0;
    const auto u16 = [&](std::uint32_t at) {
      return little ? static_cast<std::uint32_t>(msg.buffer[at] | (msg.buffer[at + 1] << 8))
                    : static_cast<std::uint32_t>((msg.buffer[at] << 8) | msg.buffer[at + 1]);
    };
    const auto u32 = [&](std::uint32_t at) {
      return little ? (u16(at) | (u16(at + 2) << 16)) : ((u16(at) << 16) | u16(at + 2));
    };
    const std::uint32_t length = u16(pos + 2);
    const std::uint32_t body = pos + 4;
    // DATA: extra flags (2), octets to inline QoS (2), reader id (4), writer id (4), sequence
    // number (high 4, low 4).
    if (id == 0x15 && body + 20 <= msg.length) {
      DataSubmessage data;
      data.writer_id = msg.buffer + body + 8;
      data.sequence = (static_cast<std::uint64_t>(u32(body + 12)) << 32) | u32(body + 16);
      if (pred(data)) return true;
    }
    if (length == 0) break;  // the last submessage runs to the end
    pos = body + length;
  }
  return false;
}

}  // namespace handshare::dds::test_support
