#pragma once
/// The shared shape of every node's main(): parse options, build, run, and map exceptions to
/// exit codes (2: bad option, 1: any other error), with the error printed once to stderr.
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "handshare/common/options.hpp"
#include "handshare/common/peers.hpp"

namespace handshare::common {

/// The options every node shares: where the session is, how long to run, which QoS file.
struct SessionOptions {
  int domain_id = 0;
  std::string session;
  std::chrono::duration<double> duration{0.0};  // 0: until SIGINT/SIGTERM
  std::string qos_file;                          // "": the default profiles
  std::vector<Peer> peers;                       // --peers: unicast discovery (docs/network.md)
};

/// Declares --domain, --session (required), --duration, --qos and --peers.
void DeclareSessionOptions(Options& options);
/// Reads them back after parsing; throws OptionError for a bad value.
SessionOptions ReadSessionOptions(const Options& options);

/// Runs body(options) after parsing; returns the process exit code.
int RunNodeMain(int argc, const char* const argv[], Options& options,
                const std::function<int(const Options&)>& body);

}  // namespace handshare::common
