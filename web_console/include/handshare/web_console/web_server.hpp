#pragma once
/// The console's HTTP and WebSocket side (Boost.Beast over Boost.Asio, OpenSSL for TLS), on a
/// thread of its own. It serves the pages' files from memory (read once at start: nothing is
/// fetched or read at run time), the state document (GET /api/state), the state pushed to every
/// viewer (WebSocket /ws) and the actions (POST /api/world, and POST /api/visit: a visitor's
/// questionnaire). Every input is checked (request_checks.hpp): sizes, rates per address, the
/// action's schema, its token, the Origin.
/// A viewer whose queue of unsent states is full is dropped: the session's side never waits for
/// a browser. Not real-time.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "handshare/web_console/request_checks.hpp"

namespace handshare::web_console {

struct WebServerConfig {
  std::string address = "127.0.0.1";    ///< listen here (an IPv4 or IPv6 literal)
  std::uint16_t port = 8080;            ///< 0: any free port (see WebServer::port)
  std::filesystem::path tls_cert;       ///< PEM; with tls_key: HTTPS and WSS only
  std::filesystem::path tls_key;
  std::string token;                    ///< the operator's token; "": actions are off (403)
  /// Files served, by URL path ("/operator" -> the file's content), read at start.
  std::map<std::string, std::filesystem::path> files;
  std::size_t max_connections = 64;     ///< HTTP and WebSocket together; more are closed at once
  std::size_t max_viewer_queue = 8;     ///< states waiting for one viewer; one more drops it
  double requests_per_s = 20.0;         ///< per address, all requests (burst 2x)
  double actions_per_min = 12.0;        ///< per address, POST /api/world, /api/visit and /api/command, refused ones too (burst 5)
};

/// The answer to an action: an HTTP status and a JSON body.
struct ActionReply {
  int status = 200;
  std::string json;
};

/// Counts for the state document and the exit summary (read from any thread).
struct WebServerCounts {
  std::uint64_t viewers = 0;          ///< WebSocket viewers now
  std::uint64_t viewers_total = 0;
  std::uint64_t viewers_dropped = 0;  ///< dropped for a full queue
  std::uint64_t requests = 0;
  std::uint64_t refused = 0;          ///< answered with a 4xx, or closed for an oversized or bad input
  std::uint64_t bytes_sent = 0;       ///< WebSocket payload bytes written to viewers
};

class WebServer {
 public:
  /// The state document for GET /api/state and a new viewer's first message; called on the
  /// server's thread.
  using StateSource = std::function<std::string()>;
  /// A checked, authorized world change; called on the server's thread.
  using WorldHandler = std::function<ActionReply(const WorldRequest&)>;
  /// A checked, authorized questionnaire; called on the server's thread.
  using VisitHandler = std::function<ActionReply(const controls::VisitAnswers&)>;
  /// A checked, authorized operator's command (restart the tour, end a turn); called on the
  /// server's thread.
  using CommandHandler = std::function<ActionReply(const controls::OperatorCommand&)>;

  /// Binds and starts serving. Without `visit`, POST /api/visit is not a path (404); without
  /// `command`, POST /api/command. Throws std::runtime_error naming the address, a file or the
  /// TLS setup that failed.
  WebServer(WebServerConfig config, StateSource state, WorldHandler world, VisitHandler visit = {},
            CommandHandler command = {});
  ~WebServer();
  WebServer(const WebServer&) = delete;
  WebServer& operator=(const WebServer&) = delete;

  /// The port it listens on (the one chosen when config.port was 0).
  std::uint16_t port() const noexcept;
  bool tls() const noexcept;
  /// Sends `json` to every viewer. Thread-safe, never blocks on a viewer.
  void Broadcast(std::string json);
  WebServerCounts counts() const;

  class Impl;  // public only so that the sessions in web_server.cpp can name it

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace handshare::web_console
