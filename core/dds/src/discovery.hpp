#pragma once
// Private to the DDS layer: how a participant finds the others (its participant id, and the
// initial peers of --peers). Includes Fast DDS headers, so only core/dds/src includes it.
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <string>

#include "handshare/common/session_options.hpp"

namespace handshare::dds::detail {

/// Participant ids a node may take when it is given --peers: a peer given by host only is
/// announced to on the discovery ports of exactly these ids (7400 + 250 d + 10 + 2 id, for
/// the default port parameters), so every node of a session without multicast must take one.
constexpr int kPeerParticipantIds = 16;
/// Participant ids a node takes without --peers (multicast discovery).
constexpr int kParticipantIds = 120;

/// Sets qos's participant id (unless its profile fixed one) and, with where.peers, its initial
/// peers: every peer's unicast discovery locator(s), and this host's loopback for the
/// participants on the same host (initial peers replace the multicast announcement). Throws
/// DdsError when a peer's port range does not fit the domain.
void ConfigureDiscovery(const common::SessionOptions& where, eprosima::fastdds::dds::DomainParticipantQos& qos);

/// Where this host's participants note, per domain, the id after the last one they took (a
/// lock-guarded file of one 32-bit integer per domain; tmpfs, gone at reboot).
inline constexpr const char* kParticipantIdLedger = "/dev/shm/handshare_participant_ids";

/// A participant id in [0, ids) whose two unicast ports are free, searching from the id after
/// the last one the ledger notes for this domain (at random if it notes none or cannot be
/// used), and noting the one taken; -1 (Fast DDS picks) if none is free.
int FreshParticipantId(int domain_id, int ids, const eprosima::fastrtps::rtps::PortParameters& ports,
                       const std::string& ledger);

}  // namespace handshare::dds::detail
