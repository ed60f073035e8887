#pragma once
/// Where a node's session is: the options every node shares, as plain data. The node layer
/// fills them from the command line (handshare/node/node_main.hpp, where `--peers` names are
/// resolved); the DDS layer's participant joins with them.
#include <chrono>
#include <string>
#include <vector>

namespace handshare::common {

/// One entry of --peers: a host, and optionally the unicast discovery (metatraffic) port of one
/// participant on it.
struct Peer {
  std::string text;  ///< as given, for messages
  std::string ipv4;  ///< the host's IPv4 address, dotted (names are resolved when parsed)
  int port = 0;      ///< 0: every handshare participant of the domain on that host
};

/// The options every node shares: where the session is, how long to run, which QoS file.
struct SessionOptions {
  int domain_id = 0;
  std::string session;
  std::chrono::duration<double> duration{0.0};  // 0: until SIGINT/SIGTERM
  std::string qos_file;                          // "": the default profiles
  std::vector<Peer> peers;                       // --peers: unicast discovery (docs/network.md)
  std::string security_dir;                      // "": no DDS-Security (docs/security.md)
};

}  // namespace handshare::common
