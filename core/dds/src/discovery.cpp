// How a participant finds the others: its participant id (its ports), and where it announces
// itself besides the multicast group (--peers). docs/network.md, "Networks without multicast".
#include "discovery.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/file.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fastdds/rtps/common/Locator.h>
#include <fastrtps/utils/IPLocator.h>

#include <cstdint>
#include <random>
#include <string>

#include "handshare/dds/participant.hpp"

namespace handshare::dds::detail {

namespace fdds = eprosima::fastdds::dds;
using eprosima::fastrtps::rtps::IPLocator;
using eprosima::fastrtps::rtps::Locator_t;
using eprosima::fastrtps::rtps::PortParameters;

namespace {

bool UdpPortFree(int port) {
  const int fd = socket(AF_INET, SOCK_DGRAM, 0);
  if (fd < 0) return false;
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_ANY);
  const bool free = bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
  close(fd);
  return free;
}

// RTPS well-known ports (DDSI-RTPS 9.6.1.1): the metatraffic unicast port of participant id;
// the user unicast port is 1 above it with the default parameters (offsetd3 = offsetd1 + 1).
int MetatrafficPort(const PortParameters& p, int domain_id, int id) {
  return p.portBase + p.domainIDGain * domain_id + p.offsetd1 + p.participantIDGain * id;
}
int UserPort(const PortParameters& p, int domain_id, int id) {
  return p.portBase + p.domainIDGain * domain_id + p.offsetd3 + p.participantIDGain * id;
}

Locator_t Udp(const std::string& ipv4, int port) {
  Locator_t l;
  l.kind = LOCATOR_KIND_UDPv4;
  IPLocator::setIPv4(l, ipv4);
  l.port = static_cast<std::uint32_t>(port);
  return l;
}

}  // namespace

// Fast DDS takes the lowest free id: a process restarted at once (a killed server, a crashed
// haptic node) then gets the id, and the ports, of the participant it replaces, and the others,
// who still hold that dead participant until its lease ends, took 2.2-3.6 s to match the new
// one (0.3 s with other ports; tests/server_crash_test.py). A random start left that to chance:
// about one restart in 16 with --peers (one in 120 without, where session.server_crash once
// took 2.8 s). So this host's participants take ids in turn: the ledger keeps, per domain, the
// id after the last one taken, under a lock, and the search starts there; a restarted process
// gets another id until all of them have been handed out since. Without the ledger (it cannot
// be opened or locked), a random start as before. Ids whose ports would pass 65535 (high
// domains) are never taken: Fast DDS exits the process on those.
int FreshParticipantId(int domain_id, int ids, const PortParameters& ports, const std::string& ledger) {
  constexpr int kLedgerDomains = 1024;  // the RTPS port formula allows 0..232 with default ports
  const bool noted = domain_id >= 0 && domain_id < kLedgerDomains && !ledger.empty();
  const int fd = noted ? open(ledger.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666) : -1;
  const bool locked = fd >= 0 && flock(fd, LOCK_EX) == 0;
  const off_t at = static_cast<off_t>(sizeof(std::int32_t)) * domain_id;
  std::int32_t next = 0;  // the id after the last one taken, plus one; 0: none noted
  if (!locked || pread(fd, &next, sizeof next, at) != static_cast<ssize_t>(sizeof next) || next <= 0) next = 0;
  int start = 0;
  if (next > 0) {
    start = (next - 1) % ids;
  } else {
    std::random_device seed;
    start = static_cast<int>(seed() % static_cast<unsigned>(ids));
  }
  int taken = -1;
  for (int k = 0; k < ids && taken < 0; ++k) {
    const int id = (start + k) % ids;
    const int metatraffic = MetatrafficPort(ports, domain_id, id);
    const int user = UserPort(ports, domain_id, id);
    if (metatraffic > 65535 || user > 65535) continue;
    if (UdpPortFree(metatraffic) && UdpPortFree(user)) taken = id;
  }
  if (taken >= 0 && locked) {
    const std::int32_t after = (taken + 1) % ids + 1;
    (void)!pwrite(fd, &after, sizeof after, at);  // unwritten: the next search starts at random
  }
  if (fd >= 0) close(fd);  // and the lock with it
  return taken;
}

void ConfigureDiscovery(const common::SessionOptions& where, fdds::DomainParticipantQos& qos) {
  const PortParameters& ports = qos.wire_protocol().port;
  const bool unicast = !where.peers.empty();
  // With peers, an id a host-only peer covers (kPeerParticipantIds): the others announce to
  // exactly those ports.
  if (qos.wire_protocol().participant_id < 0) {
    qos.wire_protocol().participant_id =
        FreshParticipantId(where.domain_id, unicast ? kPeerParticipantIds : kParticipantIds, ports, kParticipantIdLedger);
    if (unicast && qos.wire_protocol().participant_id < 0) {
      throw DdsError("DDS: --peers: no free participant id in 0.." + std::to_string(kPeerParticipantIds - 1) +
                     " on this host for domain " + std::to_string(where.domain_id) + " (at most " +
                     std::to_string(kPeerParticipantIds) + " nodes per host and domain without multicast)");
    }
  }
  if (!unicast) return;  // multicast discovery, Fast DDS's default initial peer
  // Initial peers replace the multicast announcement (Fast DDS keeps listening on the group):
  // this host's other participants are reached on the loopback, the peers on their addresses.
  auto& initial = qos.wire_protocol().builtin.initialPeersList;
  const auto add = [&](const std::string& ipv4, int port) {  // once each (a peer may be listed twice)
    const Locator_t l = Udp(ipv4, port);
    for (const Locator_t& known : initial) {
      if (known == l) return;
    }
    initial.push_back(l);
  };
  const auto add_host = [&](const std::string& ipv4) {
    for (int id = 0; id < kPeerParticipantIds; ++id) {
      const int port = MetatrafficPort(ports, where.domain_id, id);
      if (port <= 65535) add(ipv4, port);
    }
  };
  add_host("127.0.0.1");
  for (const common::Peer& peer : where.peers) {
    if (peer.port != 0) {
      add(peer.ipv4, peer.port);
    } else {
      add_host(peer.ipv4);
    }
  }
}

}  // namespace handshare::dds::detail
