// The participant id and initial peers a node's options give (--peers), and two participants
// that find each other by unicast alone.
#include "../src/discovery.hpp"

#include <gtest/gtest.h>

#include <fastrtps/utils/IPLocator.h>

#include <chrono>
#include <set>
#include <thread>

#include "handshare/dds/messages.hpp"

namespace handshare::dds {
namespace {

using eprosima::fastrtps::rtps::IPLocator;
namespace fdds = eprosima::fastdds::dds;

common::SessionOptions Where(int domain, const std::string& peers) {
  common::SessionOptions where;
  where.domain_id = domain;
  where.session = "s";
  where.peers = common::ParsePeers(peers);
  return where;
}

TEST(Discovery, WithoutPeersMulticastAsBefore) {
  fdds::DomainParticipantQos qos;
  detail::ConfigureDiscovery(Where(152, ""), qos);
  EXPECT_TRUE(qos.wire_protocol().builtin.initialPeersList.empty());  // Fast DDS: the multicast group
  EXPECT_GE(qos.wire_protocol().participant_id, 0);
  EXPECT_LT(qos.wire_protocol().participant_id, detail::kParticipantIds);
}

TEST(Discovery, HostPeersCoverEveryIdANodeWithPeersTakes) {
  fdds::DomainParticipantQos qos;
  detail::ConfigureDiscovery(Where(150, "10.1.2.3,10.1.2.4:7777,127.0.0.1,10.1.2.3"), qos);
  const int id = qos.wire_protocol().participant_id;
  EXPECT_GE(id, 0);
  EXPECT_LT(id, detail::kPeerParticipantIds);
  std::set<std::pair<std::string, std::uint32_t>> got;
  for (const auto& l : qos.wire_protocol().builtin.initialPeersList) {
    got.insert({IPLocator::ip_to_string(l), l.port});
  }
  EXPECT_EQ(got.size(), qos.wire_protocol().builtin.initialPeersList.size());  // each locator once
  std::set<std::pair<std::string, std::uint32_t>> expected{{"10.1.2.4", 7777}};
  for (std::uint32_t k = 0; k < detail::kPeerParticipantIds; ++k) {
    const std::uint32_t port = 7400 + 250 * 150 + 10 + 2 * k;  // DDSI-RTPS 9.6.1.1
    expected.insert({"10.1.2.3", port});
    expected.insert({"127.0.0.1", port});  // this host's other nodes
  }
  EXPECT_EQ(got, expected);
}

TEST(Discovery, IdsWhosePortsPass65535AreNeverTaken) {
  // Domain 232: ids above 62 would put the ports past 65535 (Fast DDS then exits).
  for (int k = 0; k < 20; ++k) {
    const int id = detail::FreshParticipantId(232, detail::kParticipantIds, eprosima::fastrtps::rtps::PortParameters());
    EXPECT_LE(7400 + 250 * 232 + 11 + 2 * id, 65535) << id;
  }
}

TEST(Discovery, TwoParticipantsWithPeersMatchOnLoopback) {
  Participant a(Where(153, "127.0.0.1"), "a"), b(Where(153, "127.0.0.1"), "b");
  auto writer = a.CreateWriter<msg::MessageBoard>("handshare/discovery_test", "state_writer");
  auto reader = b.CreateReader<msg::MessageBoard>("handshare/discovery_test", "state_reader");
  const auto end = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (reader.matched_writers() == 0 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(reader.matched_writers(), 1);
}

}  // namespace
}  // namespace handshare::dds
