#pragma once
/// Initial peers for networks without multicast (option --peers): where a node sends its
/// discovery announcements besides the multicast group. Parsing and name resolution only; the
/// DDS layer turns them into locators (core/dds/src/discovery.cpp).
#include <string_view>
#include <vector>

#include "handshare/common/session_options.hpp"

namespace handshare::node {

/// Parses "host[:port],host[:port],..." (empty: no peers). host: an IPv4 address or a name that
/// resolves to one; port: 1..65535. Throws common::OptionError naming the option and the bad
/// entry.
std::vector<common::Peer> ParsePeers(std::string_view list);

}  // namespace handshare::node
