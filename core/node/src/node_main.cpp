#include "handshare/node/node_main.hpp"

#include <exception>
#include <iostream>

#include "handshare/common/shutdown.hpp"
#include "handshare/node/peers.hpp"

namespace handshare::node {

using common::InstallShutdownHandlers;
using common::OptionError;
using common::Options;
using common::SessionOptions;

void DeclareSessionOptions(Options& options) {
  options.Value("domain", "D", "DDS domain id (0..232)", "0")
      .Value("session", "S", "session name (the DDS partition)", std::nullopt, true)
      .Value("duration", "SEC", "run this long, then end (0: until SIGINT/SIGTERM)", "0")
      .Value("qos", "FILE", "QoS profile XML (default: $HANDSHARE_QOS_FILE, else handshare_qos.xml of the "
                        "installed share/handshare/qos or the source tree's deploy/qos)", "")
      .Value("peers", "HOST[:PORT],...", "unicast discovery where multicast does not pass: the hosts (or one "
                                        "participant's discovery port) to announce to; give it to every node", "")
      .Value("security", "DIR", "DDS-Security keystore (deploy/security/make_keystore.sh): join with this "
                                "node's identity in DIR; without it, no security", "");
}

SessionOptions ReadSessionOptions(const Options& options) {
  SessionOptions s;
  s.domain_id = static_cast<int>(options.GetInt("domain", 0, 232));
  s.session = options.GetString("session");
  s.duration = std::chrono::duration<double>(options.GetDouble("duration", 0.0, 1e7));
  s.qos_file = options.GetString("qos");
  s.peers = ParsePeers(options.GetString("peers"));
  s.security_dir = options.GetString("security");
  return s;
}

int RunNodeMain(int argc, const char* const argv[], Options& options,
                const std::function<int(const Options&)>& body) {
  try {
    if (!options.Parse(argc, argv)) return 0;  // --help
  } catch (const OptionError& e) {
    std::cerr << argv[0] << ": " << e.what() << "\n(run with --help for usage)\n";
    return 2;
  }
  InstallShutdownHandlers();
  try {
    return body(options);
  } catch (const OptionError& e) {
    std::cerr << argv[0] << ": " << e.what() << "\n(run with --help for usage)\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << argv[0] << ": error: " << e.what() << "\n";
    return 1;
  }
}

}  // namespace handshare::node
