// The repair timing of Fast DDS 2.9.1's endpoint discovery (SEDP), as the user writers'.
//
// When two participants find each other, each sends the other its endpoints (the writers' and
// readers' announcements) on reliable built-in writers. Fast DDS 2.9.1 gives those writers a
// heartbeat period of 1 s and a NACK response delay of 100 ms, fixed in EDPSimple.cpp. A
// reader that lacks an announcement asks for it only when a heartbeat comes, so when a lost
// datagram is followed by a lost repair (the reader's NACK, or the resent announcement) the
// endpoints match a whole second later. On links with 2 % loss that is one rejoin in about
// twenty: a user back from a partition 1.14 and 1.27 s after the heal instead of 0.1-0.3 s
// (net.partitioned_user, which allows 1 s), a late spectator's first field 1.25 s after it
// joined (docs/network.md).
//
// The library builds these writers' attributes in EDPSimple::set_builtin_writer_attributes, a
// virtual function its vtables reach through a symbol, so this executable's definition below
// takes its place. It runs the library's own and then gives the times of the user writers
// (deploy/qos/handshare_qos.xml): a heartbeat every 50 ms and a 5 ms response. Heartbeats go
// only while a reader has not acknowledged everything: once discovery is done they stop.
//
// tests: EdpHeartbeat.* (core/dds/test/edp_heartbeat_test.cpp), with a helper whose
// announcements are lost twice; the same helper without this file matches over 1 s later.
#include "edp_heartbeat.hpp"

#include <fastdds/rtps/attributes/WriterAttributes.h>
#include <fastdds/rtps/builtin/discovery/endpoint/EDPSimple.h>

#include "library_override.hpp"

namespace {

constexpr const char* kWriterAttributesSymbol =
    "_ZN8eprosima8fastrtps4rtps9EDPSimple29set_builtin_writer_attributesERNS1_16WriterAttributesE";

using WriterAttributesFn = void (*)(eprosima::fastrtps::rtps::EDPSimple*, eprosima::fastrtps::rtps::WriterAttributes&);

WriterAttributesFn LibraryWriterAttributes() {
  static const WriterAttributesFn library = reinterpret_cast<WriterAttributesFn>(
      handshare::dds::detail::LibraryDefinition(kWriterAttributesSymbol, "EDPSimple::set_builtin_writer_attributes"));
  return library;
}

eprosima::fastrtps::Duration_t ToDuration(std::chrono::milliseconds ms) {
  return eprosima::fastrtps::Duration_t(static_cast<std::int32_t>(ms.count() / 1000),
                                        static_cast<std::uint32_t>((ms.count() % 1000) * 1000000));
}

}  // namespace

namespace eprosima::fastrtps::rtps {

void EDPSimple::set_builtin_writer_attributes(WriterAttributes& attributes) {
  LibraryWriterAttributes()(this, attributes);
  attributes.times.heartbeatPeriod = ToDuration(handshare::dds::detail::kEdpHeartbeatPeriod);
  attributes.times.nackResponseDelay = ToDuration(handshare::dds::detail::kEdpNackResponseDelay);
}

}  // namespace eprosima::fastrtps::rtps

namespace handshare::dds::detail {

bool EdpHeartbeatShortened() {
  return OverrideInEffect(kWriterAttributesSymbol, reinterpret_cast<void*>(LibraryWriterAttributes()));
}

}  // namespace handshare::dds::detail
