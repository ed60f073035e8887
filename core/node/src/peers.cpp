#include "handshare/node/peers.hpp"

#include <arpa/inet.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <charconv>

#include "handshare/common/options.hpp"

namespace handshare::node {

using common::OptionError;
using common::Peer;

namespace {

[[noreturn]] void Bad(std::string_view entry, const std::string& why) {
  throw OptionError("option --peers: '" + std::string(entry) + "': " + why +
                    " (expected host[:port],... with host an IPv4 address or name, port 1..65535)");
}

// The host's IPv4 address: a dotted address as it is, a name through the resolver (once, at
// start-up: a name that later points elsewhere needs a restart).
std::string ResolveIpv4(std::string_view entry, const std::string& host) {
  in_addr parsed{};
  if (inet_pton(AF_INET, host.c_str(), &parsed) == 1) return host;
  if (host.find(':') != std::string::npos || host.front() == '[') Bad(entry, "IPv6 is not supported");
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* found = nullptr;
  const int rc = getaddrinfo(host.c_str(), nullptr, &hints, &found);
  if (rc != 0 || found == nullptr) Bad(entry, "cannot resolve host '" + host + "' (" + gai_strerror(rc) + ")");
  char text[INET_ADDRSTRLEN] = {};
  const auto* address = reinterpret_cast<const sockaddr_in*>(found->ai_addr);
  inet_ntop(AF_INET, &address->sin_addr, text, sizeof text);
  freeaddrinfo(found);
  return text;
}

Peer ParseOne(std::string_view entry) {
  Peer peer;
  peer.text = std::string(entry);
  if (entry.empty()) Bad(entry, "empty entry");
  std::string_view host = entry;
  if (const auto colon = entry.rfind(':'); colon != std::string_view::npos && entry.front() != '[' &&
                                           entry.find(':') == colon) {
    host = entry.substr(0, colon);
    const std::string_view port = entry.substr(colon + 1);
    int value = 0;
    const auto [end, ec] = std::from_chars(port.data(), port.data() + port.size(), value);
    if (port.empty() || ec != std::errc() || end != port.data() + port.size()) {
      Bad(entry, "port '" + std::string(port) + "' is not a number");
    }
    if (value < 1 || value > 65535) Bad(entry, "port " + std::to_string(value) + " is not in 1..65535");
    peer.port = value;
  }
  if (host.empty()) Bad(entry, "no host");
  for (const char c : host) {
    if (c == ' ' || c == '\t' || c == '/' || c == '@') Bad(entry, "'" + std::string(1, c) + "' in the host");
  }
  peer.ipv4 = ResolveIpv4(entry, std::string(host));
  return peer;
}

}  // namespace

std::vector<Peer> ParsePeers(std::string_view list) {
  std::vector<Peer> peers;
  if (list.empty()) return peers;
  std::size_t begin = 0;
  while (true) {
    const std::size_t comma = list.find(',', begin);
    peers.push_back(ParseOne(list.substr(begin, comma == std::string_view::npos ? list.npos : comma - begin)));
    if (comma == std::string_view::npos) break;
    begin = comma + 1;
  }
  return peers;
}

}  // namespace handshare::node
