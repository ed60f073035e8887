#include "handshare/web_console/web_server.hpp"

#include <atomic>
#include <deque>
#include <fstream>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <type_traits>
#include <vector>

// Asio's scheduler (boost/asio/detail/impl/scheduler.ipp), inlined at -O2, trips gcc 12's
// -Wnull-dereference: a false positive in a system header, silenced for Boost's lines only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <boost/asio/ip/tcp.hpp>
#include <boost/asio/ssl.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/ssl.hpp>
#include <boost/beast/websocket.hpp>
#include <boost/beast/websocket/ssl.hpp>
#pragma GCC diagnostic pop
#include <nlohmann/json.hpp>

namespace handshare::web_console {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
namespace ssl = net::ssl;
using tcp = net::ip::tcp;
using Request = http::request<http::string_body>;
using Response = http::response<http::string_body>;
using TlsStream = beast::ssl_stream<beast::tcp_stream>;

namespace {

constexpr std::size_t kMaxHeaderBytes = 8 * 1024;
constexpr std::size_t kMaxTargetChars = 512;
constexpr std::size_t kMaxViewerMessageBytes = 512;  // viewers send nothing; a larger frame closes at once
constexpr int kSendBufferBytes = 64 * 1024;          // a viewer that stops reading fills its queue soon
constexpr auto kReadTimeout = std::chrono::seconds(15);
constexpr const char* kServerName = "handshare-web-console";
// The pages load their scripts and styles from the console only and talk to it only.
constexpr const char* kContentSecurityPolicy =
    "default-src 'none'; script-src 'self'; style-src 'self'; img-src 'self' data:; connect-src 'self'; "
    "base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

template <class S>
inline constexpr bool kIsTls = std::is_same_v<S, TlsStream>;

std::string ContentType(const std::filesystem::path& file) {
  const std::string ext = file.extension().string();
  if (ext == ".html") return "text/html; charset=utf-8";
  if (ext == ".js" || ext == ".mjs") return "text/javascript; charset=utf-8";
  if (ext == ".css") return "text/css; charset=utf-8";
  if (ext == ".json") return "application/json";
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".gltf") return "model/gltf+json";
  if (ext == ".png") return "image/png";
  if (ext == ".svg") return "image/svg+xml";
  return "application/octet-stream";
}

std::string ErrorJson(const std::string& error) {
  return nlohmann::json{{"error", error}}.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

bool IsHttpParseError(const beast::error_code& ec) {
  return &ec.category() == &http::make_error_code(http::error::bad_target).category();
}

// Closes a connection's socket when its last owner goes: the count of open connections.
struct ConnectionSlot {
  explicit ConnectionSlot(std::shared_ptr<std::atomic<std::size_t>> count) : count_(std::move(count)) { ++*count_; }
  ~ConnectionSlot() { --*count_; }
  ConnectionSlot(const ConnectionSlot&) = delete;
  ConnectionSlot& operator=(const ConnectionSlot&) = delete;
  std::shared_ptr<std::atomic<std::size_t>> count_;
};

class Viewer {
 public:
  virtual ~Viewer() = default;
  virtual void Send(const std::shared_ptr<const std::string>& message) = 0;
};

}  // namespace

class WebServer::Impl {
 public:
  Impl(WebServerConfig config, StateSource state, WorldHandler world, VisitHandler visit, CommandHandler command);
  ~Impl();

  struct File {
    std::string body;
    std::string type;
  };

  net::io_context ioc_{1};
  WebServerConfig config_;
  StateSource state_;
  WorldHandler world_;
  VisitHandler visit_;
  CommandHandler command_;
  std::optional<ssl::context> tls_;
  tcp::acceptor acceptor_{ioc_};
  std::uint16_t port_ = 0;
  std::map<std::string, File> files_;
  // Only the server's thread touches these.
  RateLimiter requests_;
  RateLimiter actions_;
  std::map<Viewer*, std::shared_ptr<Viewer>> viewers_;
  // Read from any thread.
  std::shared_ptr<std::atomic<std::size_t>> connections_ = std::make_shared<std::atomic<std::size_t>>(0);
  std::atomic<std::uint64_t> viewers_total_{0}, viewers_dropped_{0}, requests_count_{0}, refused_{0}, bytes_sent_{0},
      live_viewers_{0};
  std::thread thread_;

  void Accept();
  void OnAccept(tcp::socket socket);
  Response Respond(const Request& req, const std::string& remote, bool tls);
  /// An action's checks (rate, token, Origin, Content-Type), then its body's and its handler.
  Response Act(const Request& req, const std::string& remote, bool tls, const std::string& path);
  Response Reply(const Request& req, http::status status, std::string body, const std::string& type);
  void Join(const std::shared_ptr<Viewer>& v) {
    viewers_[v.get()] = v;
    ++viewers_total_;
    live_viewers_ = viewers_.size();
  }
  void Leave(Viewer* v) {
    viewers_.erase(v);
    live_viewers_ = viewers_.size();
  }
};

namespace {

// One viewer's WebSocket: states go out in order through a bounded queue; anything the viewer
// sends is a breach (viewers only listen), and a full queue drops the viewer.
template <class Stream>
class ViewerSession : public Viewer, public std::enable_shared_from_this<ViewerSession<Stream>> {
 public:
  ViewerSession(Stream&& stream, WebServer::Impl& server, std::unique_ptr<ConnectionSlot> slot)
      : ws_(std::move(stream)), server_(server), slot_(std::move(slot)) {}

  void Run(Request req) {
    websocket::stream_base::timeout t{};
    t.handshake_timeout = std::chrono::seconds(10);
    t.idle_timeout = std::chrono::seconds(20);  // a ping at half of it; no answer: closed
    t.keep_alive_pings = true;
    ws_.set_option(t);
    ws_.set_option(websocket::stream_base::decorator(
        [](websocket::response_type& res) { res.set(http::field::server, kServerName); }));
    ws_.read_message_max(kMaxViewerMessageBytes);
    ws_.async_accept(req, [self = this->shared_from_this()](beast::error_code ec) { self->OnAccept(ec); });
  }

  void Send(const std::shared_ptr<const std::string>& message) override {
    if (closing_) return;
    if (queue_.size() >= server_.config_.max_viewer_queue) {
      ++server_.viewers_dropped_;
      Drop();
      return;
    }
    queue_.push_back(message);
    if (queue_.size() == 1) Write();
  }

 private:
  void OnAccept(beast::error_code ec) {
    if (ec) {
      ++server_.refused_;
      return;
    }
    server_.Join(this->shared_from_this());
    Send(std::make_shared<const std::string>(server_.state_()));
    Read();
  }
  void Read() {
    ws_.async_read(in_, [self = this->shared_from_this()](beast::error_code ec, std::size_t) { self->OnRead(ec); });
  }
  void OnRead(beast::error_code ec) {
    if (ec) {
      if (ec == websocket::error::message_too_big) ++server_.refused_;
      closing_ = true;
      server_.Leave(this);
      return;
    }
    // A viewer sent a message: the socket is the console's to talk on. Closed with 1008.
    ++server_.refused_;
    closing_ = true;
    server_.Leave(this);
    ws_.async_close(websocket::close_reason(websocket::close_code::policy_error, "viewers send nothing"),
                    [self = this->shared_from_this()](beast::error_code) {});
  }
  void Write() {
    ws_.text(true);
    ws_.async_write(net::buffer(*queue_.front()),
                    [self = this->shared_from_this()](beast::error_code ec, std::size_t n) { self->OnWrite(ec, n); });
  }
  void OnWrite(beast::error_code ec, std::size_t n) {
    if (ec) {
      closing_ = true;
      server_.Leave(this);
      return;
    }
    server_.bytes_sent_ += n;
    queue_.pop_front();
    if (!queue_.empty() && !closing_) Write();
  }
  void Drop() {
    closing_ = true;
    server_.Leave(this);
    beast::get_lowest_layer(ws_).close();  // pending operations end with an error and let go
  }

  websocket::stream<Stream> ws_;
  WebServer::Impl& server_;
  std::unique_ptr<ConnectionSlot> slot_;
  beast::flat_buffer in_;
  std::deque<std::shared_ptr<const std::string>> queue_;
  bool closing_ = false;
};

// One HTTP connection: requests in turn (keep-alive), each checked and answered; a WebSocket
// upgrade hands the connection to a ViewerSession.
template <class Stream>
class HttpSession : public std::enable_shared_from_this<HttpSession<Stream>> {
 public:
  HttpSession(Stream&& stream, WebServer::Impl& server, std::unique_ptr<ConnectionSlot> slot, std::string remote)
      : stream_(std::move(stream)), server_(server), slot_(std::move(slot)), remote_(std::move(remote)) {}

  void Start() {
    if constexpr (kIsTls<Stream>) {
      beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(10));
      stream_.async_handshake(ssl::stream_base::server, [self = this->shared_from_this()](beast::error_code ec) {
        if (ec) {
          ++self->server_.refused_;  // not TLS, or a failed handshake
          return;
        }
        self->Read();
      });
    } else {
      Read();
    }
  }

 private:
  void Read() {
    parser_.emplace();
    parser_->header_limit(kMaxHeaderBytes);
    parser_->body_limit(kMaxActionBodyBytes);
    beast::get_lowest_layer(stream_).expires_after(kReadTimeout);
    http::async_read(stream_, buffer_, *parser_,
                     [self = this->shared_from_this()](beast::error_code ec, std::size_t) { self->OnRead(ec); });
  }

  void OnRead(beast::error_code ec) {
    if (ec == http::error::end_of_stream) return Close();
    if (ec == http::error::body_limit) return Refuse(http::status::payload_too_large, "request body too large");
    if (ec == http::error::header_limit) {
      return Refuse(http::status::request_header_fields_too_large, "request header too large");
    }
    if (ec && IsHttpParseError(ec)) return Refuse(http::status::bad_request, "malformed request: " + ec.message());
    if (ec) return;  // timeout, reset: the stream is closed with its last owner
    Request req = parser_->release();
    ++server_.requests_count_;
    const auto now = std::chrono::steady_clock::now();
    if (!server_.requests_.Allow(remote_, now)) {
      Response res = server_.Reply(req, http::status::too_many_requests, ErrorJson("too many requests"), "application/json");
      res.set(http::field::retry_after, std::to_string(server_.requests_.RetryAfterS(remote_, now)));
      return Send(std::move(res));
    }
    if (websocket::is_upgrade(req)) return Upgrade(std::move(req));
    Send(server_.Respond(req, remote_, kIsTls<Stream>));
  }

  void Upgrade(Request req) {
    const std::string_view target(req.target().data(), req.target().size());
    if (target != "/ws") {
      return Send(server_.Reply(req, http::status::not_found, ErrorJson("no WebSocket here: /ws"), "application/json"));
    }
    const auto origin = req.find(http::field::origin);
    std::optional<std::string_view> o;
    if (origin != req.end()) o = std::string_view(origin->value().data(), origin->value().size());
    const std::string_view host(req[http::field::host].data(), req[http::field::host].size());
    if (!OriginAllowed(o, host, kIsTls<Stream>)) {
      return Send(server_.Reply(req, http::status::forbidden, ErrorJson("Origin is not this console"), "application/json"));
    }
    beast::get_lowest_layer(stream_).expires_never();  // the WebSocket's own timeouts from here
    std::make_shared<ViewerSession<Stream>>(std::move(stream_), server_, std::move(slot_))->Run(std::move(req));
  }

  void Refuse(http::status status, const std::string& why) {
    Request none;  // counted as refused by Send, as every 4xx
    Response res = server_.Reply(none, status, ErrorJson(why), "application/json");
    res.keep_alive(false);
    Send(std::move(res));
  }

  void Send(Response res) {
    if (static_cast<int>(res.result_int()) >= 400 && static_cast<int>(res.result_int()) < 500) ++server_.refused_;
    res_ = std::make_shared<Response>(std::move(res));
    http::async_write(stream_, *res_, [self = this->shared_from_this()](beast::error_code ec, std::size_t) {
      if (ec) return;
      if (self->res_->need_eof()) return self->Close();
      self->Read();
    });
  }

  void Close() {
    if constexpr (kIsTls<Stream>) {
      beast::get_lowest_layer(stream_).expires_after(std::chrono::seconds(5));
      stream_.async_shutdown([self = this->shared_from_this()](beast::error_code) {});
    } else {
      beast::error_code ec;
      stream_.socket().shutdown(tcp::socket::shutdown_send, ec);
    }
  }

  Stream stream_;
  WebServer::Impl& server_;
  std::unique_ptr<ConnectionSlot> slot_;
  std::string remote_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::shared_ptr<Response> res_;
};

}  // namespace

WebServer::Impl::Impl(WebServerConfig config, StateSource state, WorldHandler world, VisitHandler visit,
                      CommandHandler command)
    : config_(std::move(config)),
      state_(std::move(state)),
      world_(std::move(world)),
      visit_(std::move(visit)),
      command_(std::move(command)),
      requests_(config_.requests_per_s, 2.0 * config_.requests_per_s),
      actions_(config_.actions_per_min / 60.0, 5.0) {
  for (const auto& [url, path] : config_.files) {
    std::ifstream in(path, std::ios::binary);
    if (!in) throw std::runtime_error("web_console: cannot read " + path.string() + " (served at " + url + ")");
    std::ostringstream body;
    body << in.rdbuf();
    files_[url] = File{body.str(), ContentType(path)};
  }
  if (config_.tls_cert.empty() != config_.tls_key.empty()) {
    throw std::runtime_error("web_console: --tls-cert and --tls-key go together");
  }
  if (!config_.tls_cert.empty()) {
    tls_.emplace(ssl::context::tls_server);
    tls_->set_options(ssl::context::default_workarounds | ssl::context::no_sslv2 | ssl::context::no_sslv3 |
                      ssl::context::no_tlsv1 | ssl::context::no_tlsv1_1 | ssl::context::single_dh_use);
    beast::error_code ec;
    tls_->use_certificate_chain_file(config_.tls_cert.string(), ec);
    if (ec) throw std::runtime_error("web_console: --tls-cert " + config_.tls_cert.string() + ": " + ec.message());
    tls_->use_private_key_file(config_.tls_key.string(), ssl::context::pem, ec);
    if (ec) throw std::runtime_error("web_console: --tls-key " + config_.tls_key.string() + ": " + ec.message());
  }
  beast::error_code ec;
  const auto address = net::ip::make_address(config_.address, ec);
  if (ec) throw std::runtime_error("web_console: --listen address '" + config_.address + "' is not an IP address");
  const tcp::endpoint endpoint(address, config_.port);
  const std::string where = config_.address + ":" + std::to_string(config_.port);
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (!ec) acceptor_.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("web_console: cannot listen on " + where + ": " + ec.message());
  port_ = acceptor_.local_endpoint().port();
  Accept();
  thread_ = std::thread([this] { ioc_.run(); });
}

WebServer::Impl::~Impl() {
  ioc_.stop();
  if (thread_.joinable()) thread_.join();
}

void WebServer::Impl::Accept() {
  acceptor_.async_accept(ioc_, [this](beast::error_code ec, tcp::socket socket) {
    if (!ec) OnAccept(std::move(socket));
    if (acceptor_.is_open()) Accept();
  });
}

void WebServer::Impl::OnAccept(tcp::socket socket) {
  if (connections_->load() >= config_.max_connections) {
    ++refused_;
    return;  // closed as `socket` goes
  }
  beast::error_code ec;
  const std::string remote = socket.remote_endpoint(ec).address().to_string();
  if (ec) return;
  socket.set_option(net::socket_base::send_buffer_size(kSendBufferBytes), ec);
  socket.set_option(tcp::no_delay(true), ec);
  auto slot = std::make_unique<ConnectionSlot>(connections_);
  if (tls_) {
    std::make_shared<HttpSession<TlsStream>>(TlsStream(std::move(socket), *tls_), *this, std::move(slot), remote)
        ->Start();
  } else {
    std::make_shared<HttpSession<beast::tcp_stream>>(beast::tcp_stream(std::move(socket)), *this, std::move(slot),
                                                     remote)
        ->Start();
  }
}

Response WebServer::Impl::Reply(const Request& req, http::status status, std::string body, const std::string& type) {
  Response res{status, req.version() == 0 ? 11 : req.version()};
  res.set(http::field::server, kServerName);
  res.set(http::field::content_type, type);
  res.set(http::field::cache_control, "no-store");
  res.set("X-Content-Type-Options", "nosniff");
  res.set("X-Frame-Options", "DENY");
  res.set("Referrer-Policy", "no-referrer");
  res.set("Content-Security-Policy", kContentSecurityPolicy);
  res.keep_alive(req.keep_alive());
  res.body() = std::move(body);
  res.prepare_payload();
  return res;
}

Response WebServer::Impl::Respond(const Request& req, const std::string& remote, bool tls) {
  const std::string_view target(req.target().data(), req.target().size());
  if (target.size() > kMaxTargetChars) {
    return Reply(req, http::status::uri_too_long, ErrorJson("target too long"), "application/json");
  }
  const std::string path(target.substr(0, target.find('?')));
  if (path == "/api/world" || (path == "/api/visit" && visit_) || (path == "/api/command" && command_)) {
    if (req.method() != http::verb::post) {
      Response res = Reply(req, http::status::method_not_allowed, ErrorJson("POST only"), "application/json");
      res.set(http::field::allow, "POST");
      return res;
    }
    return Act(req, remote, tls, path);
  }
  if (req.method() != http::verb::get) {
    Response res = Reply(req, http::status::method_not_allowed, ErrorJson("GET only"), "application/json");
    res.set(http::field::allow, "GET");
    return res;
  }
  if (!req.body().empty()) return Reply(req, http::status::bad_request, ErrorJson("a GET has no body"), "application/json");
  if (path == "/api/state") return Reply(req, http::status::ok, state_(), "application/json");
  if (const auto it = files_.find(path); it != files_.end()) {
    return Reply(req, http::status::ok, it->second.body, it->second.type);
  }
  return Reply(req, http::status::not_found, ErrorJson("no such page: " + path.substr(0, 64)), "application/json");
}

Response WebServer::Impl::Act(const Request& req, const std::string& remote, bool tls, const std::string& path) {
  if (const auto now = std::chrono::steady_clock::now(); !actions_.Allow(remote, now)) {
    Response res = Reply(req, http::status::too_many_requests, ErrorJson("too many actions from this address"),
                         "application/json");
    res.set(http::field::retry_after, std::to_string(actions_.RetryAfterS(remote, now)));
    return res;
  }
  if (config_.token.empty()) {
    return Reply(req, http::status::forbidden,
                 ErrorJson("actions are off: the console was started without --token-file"), "application/json");
  }
  const auto origin = req.find(http::field::origin);
  std::optional<std::string_view> o;
  if (origin != req.end()) o = std::string_view(origin->value().data(), origin->value().size());
  if (!OriginAllowed(o, std::string_view(req[http::field::host].data(), req[http::field::host].size()), tls)) {
    return Reply(req, http::status::forbidden, ErrorJson("Origin is not this console"), "application/json");
  }
  const auto authorization = req[http::field::authorization];
  const auto token = BearerToken(std::string_view(authorization.data(), authorization.size()));
  if (!token || !TokensEqual(*token, config_.token)) {
    Response res = Reply(req, http::status::unauthorized, ErrorJson(token ? "wrong token" : "no token (Authorization: Bearer TOKEN)"),
                         "application/json");
    res.set(http::field::www_authenticate, "Bearer realm=\"handshare\"");
    return res;
  }
  const auto type = req[http::field::content_type];
  const std::string_view content_type(type.data(), type.size());
  if (content_type.substr(0, content_type.find(';')) != "application/json") {
    return Reply(req, http::status::unsupported_media_type, ErrorJson("Content-Type must be application/json"),
                 "application/json");
  }
  ActionReply reply;
  if (path == "/api/visit") {
    const ParsedVisitRequest parsed = ParseVisitRequest(req.body());
    if (!parsed.answers) return Reply(req, http::status::bad_request, ErrorJson(parsed.error), "application/json");
    reply = visit_(*parsed.answers);
  } else if (path == "/api/command") {
    const ParsedCommandRequest parsed = ParseCommandRequest(req.body());
    if (!parsed.command) return Reply(req, http::status::bad_request, ErrorJson(parsed.error), "application/json");
    reply = command_(*parsed.command);
  } else {
    const ParsedWorldRequest parsed = ParseWorldRequest(req.body());
    if (!parsed.request) return Reply(req, http::status::bad_request, ErrorJson(parsed.error), "application/json");
    reply = world_(*parsed.request);
  }
  return Reply(req, static_cast<http::status>(reply.status), reply.json, "application/json");
}

WebServer::WebServer(WebServerConfig config, StateSource state, WorldHandler world, VisitHandler visit,
                     CommandHandler command)
    : impl_(std::make_unique<Impl>(std::move(config), std::move(state), std::move(world), std::move(visit),
                                   std::move(command))) {}

WebServer::~WebServer() = default;

std::uint16_t WebServer::port() const noexcept { return impl_->port_; }
bool WebServer::tls() const noexcept { return impl_->tls_.has_value(); }

void WebServer::Broadcast(std::string json) {
  auto message = std::make_shared<const std::string>(std::move(json));
  net::post(impl_->ioc_, [impl = impl_.get(), message] {
    std::vector<std::shared_ptr<Viewer>> viewers;
    viewers.reserve(impl->viewers_.size());
    for (const auto& [raw, v] : impl->viewers_) viewers.push_back(v);
    for (const auto& v : viewers) v->Send(message);  // a full one leaves the map as it is dropped
  });
}

WebServerCounts WebServer::counts() const {
  WebServerCounts c;
  c.viewers_total = impl_->viewers_total_;
  c.viewers_dropped = impl_->viewers_dropped_;
  c.requests = impl_->requests_count_;
  c.refused = impl_->refused_;
  c.bytes_sent = impl_->bytes_sent_;
  c.viewers = impl_->live_viewers_;
  return c;
}

}  // namespace handshare::web_console
