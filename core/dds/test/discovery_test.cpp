// The participant id and initial peers a node's options give (--peers), and two participants
// that find each other by unicast alone.
#include "../src/discovery.hpp"

#include <gtest/gtest.h>

#include <fastrtps/utils/IPLocator.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <set>
#include <thread>

#include "handshare/dds/messages.hpp"
#include "handshare/node/peers.hpp"

namespace handshare::dds {
namespace {

using eprosima::fastrtps::rtps::IPLocator;
namespace fdds = eprosima::fastdds::dds;

common::SessionOptions Where(int domain, const std::string& peers) {
  common::SessionOptions where;
  where.domain_id = domain;
  where.session = "s";
  where.peers = node::ParsePeers(peers);
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
    const int id = detail::FreshParticipantId(232, detail::kParticipantIds, eprosima::fastrtps::rtps::PortParameters(),
                                              detail::kParticipantIdLedger);
    EXPECT_LE(7400 + 250 * 232 + 11 + 2 * id, 65535) << id;
  }
}

// A ledger of this test's own (not the host's, which other tests' nodes use at the same time).
std::string TestLedger(const char* name) {
  const std::string path = ::testing::TempDir() + "handshare_ids_" + name + "_" + std::to_string(getpid());
  std::remove(path.c_str());
  return path;
}

// A node killed and started again at once must not get its predecessor's id (its ports): the
// others still hold the dead participant and took 2.2-3.6 s to match the new one. The first
// call stands for the node that died (its ports are free again), the second for its restart.
// With a random start they met about one time in 16 (--peers' ids): in 100 restarts, all but
// certainly.
TEST(Discovery, ARestartedNodeDoesNotTakeItsPredecessorsId) {
  const std::string ledger = TestLedger("restart");
  const eprosima::fastrtps::rtps::PortParameters ports;
  int same = 0, in_turn = 0;
  for (int k = 0; k < 100; ++k) {
    const int died = detail::FreshParticipantId(161, detail::kPeerParticipantIds, ports, ledger);
    const int restarted = detail::FreshParticipantId(161, detail::kPeerParticipantIds, ports, ledger);
    ASSERT_GE(died, 0);
    ASSERT_GE(restarted, 0);
    same += died == restarted ? 1 : 0;
    in_turn += restarted == (died + 1) % detail::kPeerParticipantIds ? 1 : 0;
  }
  EXPECT_EQ(same, 0);
  EXPECT_GE(in_turn, 90);  // the next id, unless another process on this host holds its ports
  std::remove(ledger.c_str());
}

// The ledger only orders the search: an id whose port is taken is still skipped, and without a
// usable ledger the search starts at random as before.
TEST(Discovery, TheLedgerNeverGivesAnIdWhosePortsAreTaken) {
  const std::string ledger = TestLedger("busy");
  const eprosima::fastrtps::rtps::PortParameters ports;
  const int first = detail::FreshParticipantId(162, detail::kPeerParticipantIds, ports, ledger);
  ASSERT_GE(first, 0);
  const int busy = (first + 1) % detail::kPeerParticipantIds;  // the one the ledger would give next
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  ASSERT_GE(fd, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(7400 + 250 * 162 + 10 + 2 * busy));
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  ASSERT_EQ(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a), 0);
  const int next = detail::FreshParticipantId(162, detail::kPeerParticipantIds, ports, ledger);
  close(fd);
  EXPECT_NE(next, busy);
  EXPECT_NE(next, first);
  const int unnoted = detail::FreshParticipantId(162, detail::kPeerParticipantIds, ports, "/nonexistent/dir/ledger");
  EXPECT_GE(unnoted, 0);
  EXPECT_LT(unnoted, detail::kPeerParticipantIds);
  std::remove(ledger.c_str());
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
