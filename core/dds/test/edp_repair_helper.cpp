// Helper of the EdpHeartbeat tests (edp_heartbeat_test.cpp): two participants in one process,
// over UDP only, where every datagram carrying the writer's endpoint announcement (SEDP
// publications DATA) is lost for 0.25 s from the first one, as a datagram dropped on a lossy
// link (and any repair sent while the loss lasts). Prints when the reader matched the writer,
// counted from the first lost datagram.
//
// Built twice: edp_repair_helper links handshare::dds and so has src/edp_heartbeat.cpp;
// edp_repair_helper_library (HANDSHARE_LIBRARY_TIMES) links Fast DDS alone, as the control.
//
// usage: edp_repair_helper DOMAIN
// prints "heartbeat shortened" or "heartbeat the library's", then
// "dropped N datagrams; matched S s after the first", exits 0; exits 1 when nothing matched in 10 s.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/rtps/common/EntityId_t.hpp>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/test_UDPv4TransportDescriptor.h>
#include <memory>
#include <thread>

#include "handshare/idl/handsharePubSubTypes.h"
#include "rtps_test_support.hpp"

#ifndef HANDSHARE_LIBRARY_TIMES
#include "../src/edp_heartbeat.hpp"
#endif

namespace fdds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;
namespace ts = handshare::dds::test_support;
using Clock = std::chrono::steady_clock;

namespace {

constexpr auto kLossWindow = std::chrono::milliseconds(250);

std::atomic<std::int64_t> first_drop_ns{0};
std::atomic<int> dropped{0};
std::atomic<std::int64_t> matched_ns{0};

std::int64_t Now() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

// True when the RTPS message holds a DATA submessage from the SEDP publications writer.
bool CarriesAnAnnouncement(const rtps::CDRMessage_t& msg) {
  const rtps::EntityId_t pub = rtps::c_EntityId_SEDPPubWriter;
  return ts::AnyData(msg, [&](const ts::DataSubmessage& data) {
    return std::equal(pub.value, pub.value + 4, data.writer_id);
  });
}

bool DropWhileTheWindowLasts(rtps::CDRMessage_t& msg) {
  if (!CarriesAnAnnouncement(msg)) return false;
  const std::int64_t now = Now();
  std::int64_t expected = 0;
  first_drop_ns.compare_exchange_strong(expected, now);
  const std::int64_t first = first_drop_ns.load();
  if (now - first >= std::chrono::nanoseconds(kLossWindow).count()) return false;
  ++dropped;
  return true;
}

class MatchListener final : public fdds::DataReaderListener {
 public:
  void on_subscription_matched(fdds::DataReader*, const fdds::SubscriptionMatchedStatus& s) override {
    std::int64_t expected = 0;
    if (s.current_count_change > 0) matched_ns.compare_exchange_strong(expected, Now());
  }
};

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s DOMAIN\n", argv[0]);
    return 2;
  }
  const int domain = std::atoi(argv[1]);
#ifdef HANDSHARE_LIBRARY_TIMES
  std::printf("heartbeat the library's\n");
#else
  std::printf("heartbeat %s\n", handshare::dds::detail::EdpHeartbeatShortened() ? "shortened" : "the library's");
#endif
  std::fflush(stdout);
  ts::TalkOverTransports();

  auto* factory = fdds::DomainParticipantFactory::get_instance();
  fdds::DomainParticipant* reader_side =
      factory->create_participant(domain, ts::OnlyOver(std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>()));
  auto lossy = std::make_shared<eprosima::fastdds::rtps::test_UDPv4TransportDescriptor>();
  lossy->messages_filter_ = DropWhileTheWindowLasts;
  fdds::DomainParticipant* writer_side = factory->create_participant(domain, ts::OnlyOver(lossy));
  if (reader_side == nullptr || writer_side == nullptr) {
    std::fprintf(stderr, "edp_repair_helper: could not create the participants on domain %d\n", domain);
    return 1;
  }
  fdds::TypeSupport type(new handshare::msg::MemberInfoPubSubType());
  type.register_type(reader_side);
  type.register_type(writer_side);
  fdds::Topic* rt = reader_side->create_topic("edp_repair", type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  fdds::Topic* wt = writer_side->create_topic("edp_repair", type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
  MatchListener listener;
  fdds::Subscriber* sub = reader_side->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
  fdds::DataReader* reader = sub->create_datareader(rt, fdds::DATAREADER_QOS_DEFAULT, &listener);
  fdds::Publisher* pub = writer_side->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
  fdds::DataWriter* writer = pub->create_datawriter(wt, fdds::DATAWRITER_QOS_DEFAULT);
  if (reader == nullptr || writer == nullptr) {
    std::fprintf(stderr, "edp_repair_helper: could not create the endpoints\n");
    return 1;
  }
  const auto end = Clock::now() + std::chrono::seconds(10);
  while (matched_ns.load() == 0 && Clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  const std::int64_t first = first_drop_ns.load(), matched = matched_ns.load();
  writer_side->delete_contained_entities();
  reader_side->delete_contained_entities();
  factory->delete_participant(writer_side);
  factory->delete_participant(reader_side);
  if (matched == 0) {
    std::fprintf(stderr, "edp_repair_helper: the reader did not match the writer in 10 s (%d datagrams dropped)\n",
                 dropped.load());
    return 1;
  }
  std::printf("dropped %d datagrams; matched %.3f s after the first\n", dropped.load(),
              first == 0 ? -1.0 : 1e-9 * static_cast<double>(matched - first));
  return 0;
}
