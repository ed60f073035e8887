#pragma once
/// The web console node: joins a session over DDS, keeps what the operator's page shows
/// (console_state.hpp: every station's loop statistics, the world server's tick, the current
/// world, the message board, the members), pushes it to the browsers at most 5 times a second
/// and once a second at least, and turns an authorized world change from the page into the one
/// control event that goes there (world_routes.hpp). One thread for DDS, one for the web
/// (web_server.hpp). Not real-time.
#include <cstdint>
#include <filesystem>
#include <string>

#include "handshare/common/session_options.hpp"

namespace handshare::web_console {

struct ConsoleConfig {
  common::SessionOptions where;      ///< domain, session, duration, QoS, peers, security
  std::string name = "web-console";  ///< member name; the user of its control events
  std::string listen = "127.0.0.1:8080";
  std::filesystem::path token_file;  ///< "": actions are off
  std::filesystem::path tls_cert;    ///< with tls_key: HTTPS and WSS
  std::filesystem::path tls_key;
  std::filesystem::path www_dir;     ///< "": WwwDir()
  std::size_t max_connections = 64;
};

/// An ADDR:PORT of --listen: "127.0.0.1:8080", "0.0.0.0:80", "[::1]:8080". Throws
/// std::invalid_argument saying what is wrong.
struct ListenAddress {
  std::string address;
  std::uint16_t port = 0;
};
ListenAddress ParseListen(const std::string& text);

/// The pages' folder: share/handshare/www when installed, else the source tree's web_console/www.
std::filesystem::path WwwDir();

class Console {
 public:
  explicit Console(ConsoleConfig config);
  int Run();

 private:
  ConsoleConfig config_;
};

}  // namespace handshare::web_console
