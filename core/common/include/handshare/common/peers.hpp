#pragma once
/// Initial peers for networks without multicast (option --peers): where a node sends its
/// discovery announcements besides the multicast group. Parsing and name resolution only; the
/// DDS layer turns them into locators (core/dds/src/discovery.cpp).
#include <string>
#include <string_view>
#include <vector>

namespace handshare::common {

/// One entry of --peers: a host, and optionally the unicast discovery (metatraffic) port of one
/// participant on it.
struct Peer {
  std::string text;  ///< as given, for messages
  std::string ipv4;  ///< the host's IPv4 address, dotted (names are resolved when parsed)
  int port = 0;      ///< 0: every handshare participant of the domain on that host
};

/// Parses "host[:port],host[:port],..." (empty: no peers). host: an IPv4 address or a name that
/// resolves to one; port: 1..65535. Throws OptionError naming the option and the bad entry.
std::vector<Peer> ParsePeers(std::string_view list);

}  // namespace handshare::common
