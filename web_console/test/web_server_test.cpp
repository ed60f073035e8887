// The web server on loopback, driven by a plain HTTP and WebSocket client (Boost.Beast): what
// every input gets, and that a viewer that stops reading is dropped while the others go on.
#include "handshare/web_console/web_server.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <thread>

// Asio's scheduler (boost/asio/detail/impl/scheduler.ipp), inlined at -O2, trips gcc 12's
// -Wnull-dereference: a false positive in a system header, silenced for Boost's lines only.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wnull-dereference"
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#pragma GCC diagnostic pop

namespace handshare::web_console {
namespace {

namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
namespace net = boost::asio;
using tcp = net::ip::tcp;

constexpr const char* kToken = "0123456789abcdef-token";

class WebServerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    page_ = std::filesystem::temp_directory_path() / ("web_server_test_" + std::to_string(getpid()) + ".html");
    std::ofstream(page_) << "<p>operator</p>";
  }
  void Start(const std::string& token = kToken, double actions_per_min = 12.0) {
    WebServerConfig c;
    c.port = 0;
    c.token = token;
    c.actions_per_min = actions_per_min;
    c.files = {{"/operator", page_}};
    server_ = std::make_unique<WebServer>(
        c, [] { return std::string(R"({"type":"state"})"); },
        [this](const WorldRequest& r) {
          ++actions_;
          last_world_ = r.world;
          return ActionReply{202, R"({"world":")" + r.world + "\"}"};
        },
        [this](const controls::VisitAnswers& a) {
          ++visits_;
          last_visit_ = a;
          return ActionReply{202, R"({"visitor":")" + a.visitor + "\"}"};
        },
        [this](const controls::OperatorCommand& command) {
          ++commands_;
          last_command_ = command;
          return ActionReply{202, R"({"command":"x"})"};
        });
  }
  http::response<http::string_body> PostVisit(const std::string& body, const std::string& token,
                                              const std::string& type = "application/json") {
    std::map<std::string, std::string> h{{"Content-Type", type}};
    if (!token.empty()) h["Authorization"] = "Bearer " + token;
    return Request(http::verb::post, "/api/visit", body, h);
  }
  http::response<http::string_body> Request(http::verb verb, const std::string& target, const std::string& body = "",
                                            const std::map<std::string, std::string>& headers = {}) {
    net::io_context ioc;
    beast::tcp_stream stream(ioc);
    stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), server_->port()));
    http::request<http::string_body> req{verb, target, 11};
    req.set(http::field::host, "127.0.0.1:" + std::to_string(server_->port()));
    for (const auto& [k, v] : headers) req.set(k, v);
    req.body() = body;
    req.prepare_payload();
    http::write(stream, req);
    beast::flat_buffer buffer;
    http::response<http::string_body> res;
    http::read(stream, buffer, res);
    return res;
  }
  http::response<http::string_body> PostWorld(const std::string& body, const std::string& token,
                                              const std::string& type = "application/json") {
    std::map<std::string, std::string> h{{"Content-Type", type}};
    if (!token.empty()) h["Authorization"] = "Bearer " + token;
    return Request(http::verb::post, "/api/world", body, h);
  }

  std::filesystem::path page_;
  std::unique_ptr<WebServer> server_;
  std::atomic<int> actions_{0};
  std::string last_world_;
  std::atomic<int> visits_{0};
  controls::VisitAnswers last_visit_;
  std::atomic<int> commands_{0};
  controls::OperatorCommand last_command_;
};

// The operator's commands (POST /api/command): the token, the Origin, the Content-Type and a
// body of the exact schema, or a 4xx and nothing reaches the session; the shared rate.
TEST_F(WebServerTest, AnOperatorsCommandNeedsTheTokenAndAWellFormedBody) {
  Start(kToken, /*actions_per_min=*/6e6);
  const auto post = [this](const std::string& body, const std::string& token, const std::string& type = "application/json") {
    std::map<std::string, std::string> h{{"Content-Type", type}};
    if (!token.empty()) h["Authorization"] = "Bearer " + token;
    return Request(http::verb::post, "/api/command", body, h);
  };
  const std::string body = R"({"command":"end_turn","visitor":"alice"})";
  EXPECT_EQ(post(body, "").result_int(), 401u);
  EXPECT_EQ(post(body, "0123456789abcdef-wrong").result_int(), 401u);
  EXPECT_EQ(post(body, kToken, "text/plain").result_int(), 415u);
  EXPECT_EQ(Request(http::verb::post, "/api/command", body,
                    {{"Content-Type", "application/json"}, {"Authorization", std::string("Bearer ") + kToken},
                     {"Origin", "http://evil.example"}})
                .result_int(),
            403u);
  EXPECT_EQ(post(R"({"command":"reboot"})", kToken).result_int(), 400u);
  EXPECT_EQ(Request(http::verb::get, "/api/command").result_int(), 405u);
  EXPECT_EQ(commands_, 0);
  const auto ok = post(body, kToken);
  EXPECT_EQ(ok.result_int(), 202u) << ok.body();
  EXPECT_EQ(commands_, 1);
  EXPECT_EQ(last_command_.action, controls::OperatorAction::kEndTurn);
  EXPECT_EQ(last_command_.visitor, "alice");
  EXPECT_EQ(actions_, 0);
  EXPECT_EQ(visits_, 0);
}

TEST_F(WebServerTest, ServesItsPagesWithAStrictContentSecurityPolicy) {
  Start();
  const auto res = Request(http::verb::get, "/operator");
  EXPECT_EQ(res.result_int(), 200u);
  EXPECT_EQ(res.body(), "<p>operator</p>");
  EXPECT_EQ(res[http::field::content_type], "text/html; charset=utf-8");
  EXPECT_NE(res["Content-Security-Policy"].find("connect-src 'self'"), std::string::npos);
  EXPECT_EQ(Request(http::verb::get, "/api/state").body(), R"({"type":"state"})");
  EXPECT_EQ(Request(http::verb::get, "/etc/passwd").result_int(), 404u);
  EXPECT_EQ(Request(http::verb::get, "/operator/../operator").result_int(), 404u);
  EXPECT_EQ(Request(http::verb::delete_, "/operator").result_int(), 405u);
  EXPECT_EQ(Request(http::verb::get, "/api/world").result_int(), 405u);
  EXPECT_EQ(Request(http::verb::get, "/" + std::string(600, 'a')).result_int(), 414u);
}

TEST_F(WebServerTest, AWorldChangeNeedsTheTokenAndAWellFormedBody) {
  Start();
  const std::string body = R"({"world":"dinosaur"})";
  EXPECT_EQ(PostWorld(body, "").result_int(), 401u);
  const auto wrong = PostWorld(body, "0123456789abcdef-wrong");
  EXPECT_EQ(wrong.result_int(), 401u);
  EXPECT_EQ(wrong[http::field::www_authenticate], "Bearer realm=\"handshare\"");
  EXPECT_EQ(actions_, 0);  // nothing reached the session
  EXPECT_EQ(PostWorld(body, kToken, "text/plain").result_int(), 415u);
  EXPECT_EQ(PostWorld(R"({"world":"dinosaur","x":1})", kToken).result_int(), 400u);
  EXPECT_EQ(actions_, 0);
  const auto ok = PostWorld(body, kToken);
  EXPECT_EQ(ok.result_int(), 202u);
  EXPECT_EQ(actions_, 1);
  EXPECT_EQ(last_world_, "dinosaur");
}

// The questionnaire (/visit's POST): the operator's token, the Origin, the Content-Type and a
// body of the exact schema, or a 4xx and nothing reaches the session.
TEST_F(WebServerTest, AQuestionnaireNeedsTheTokenAndAWellFormedBody) {
  Start(kToken, /*actions_per_min=*/6e6);  // this test's many refusals are not about the rate
  const std::string body =
      R"({"visitor":"alice","answers":{"book":{"ease":6,"naturalness":5,"satisfaction":7}}})";
  EXPECT_EQ(PostVisit(body, "").result_int(), 401u);
  EXPECT_EQ(PostVisit(body, "0123456789abcdef-wrong").result_int(), 401u);
  EXPECT_EQ(PostVisit(body, kToken, "text/plain").result_int(), 415u);
  EXPECT_EQ(Request(http::verb::post, "/api/visit", body,
                    {{"Content-Type", "application/json"}, {"Authorization", std::string("Bearer ") + kToken},
                     {"Origin", "http://evil.example"}})
                .result_int(),
            403u);
  for (const char* bad : {R"({"visitor":"alice","answers":{"book":{"ease":8,"naturalness":5,"satisfaction":7}}})",
                          R"({"visitor":"alice","answers":{"book":{"ease":0,"naturalness":5,"satisfaction":7}}})",
                          R"({"visitor":"alice","answers":{"book":{"ease":5.5,"naturalness":5,"satisfaction":7}}})",
                          R"({"visitor":"alice","answers":{"book":{"ease":"5","naturalness":5,"satisfaction":7}}})",
                          R"({"visitor":"alice","answers":{"book":{"ease":5,"naturalness":5}}})",
                          R"({"visitor":"alice","answers":{"piano":{"ease":5,"naturalness":5,"satisfaction":7}}})",
                          R"({"visitor":"al ice","answers":{"book":{"ease":5,"naturalness":5,"satisfaction":7}}})",
                          R"({"visitor":"alice","answers":{}})", R"({"visitor":"alice"})", R"([])"}) {
    EXPECT_EQ(PostVisit(bad, kToken).result_int(), 400u) << bad;
  }
  EXPECT_EQ(PostVisit(R"({"visitor":")" + std::string(2000, 'a') + "\"}", kToken).result_int(), 413u);
  EXPECT_EQ(Request(http::verb::get, "/api/visit").result_int(), 405u);
  EXPECT_EQ(visits_, 0);  // nothing reached the session
  const auto ok = PostVisit(body, kToken);
  EXPECT_EQ(ok.result_int(), 202u) << ok.body();
  EXPECT_EQ(visits_, 1);
  EXPECT_EQ(last_visit_.visitor, "alice");
  EXPECT_EQ(last_visit_.at(scene::ControlType::kBook, controls::VisitQuestion::kSatisfaction), 7);
  EXPECT_EQ(last_visit_.at(scene::ControlType::kButton, controls::VisitQuestion::kEase), 0);  // not answered
  EXPECT_EQ(actions_, 0);  // and no world change
}

TEST_F(WebServerTest, QuestionnairesShareTheActionsRate) {
  Start();
  const std::string body =
      R"({"visitor":"alice","answers":{"book":{"ease":6,"naturalness":5,"satisfaction":7}}})";
  int limited = 0;
  for (int i = 0; i < 8; ++i) limited += PostVisit(body, "0123456789abcdef-guess").result_int() == 429u;
  EXPECT_EQ(limited, 3);  // a burst of 5, then 12 a minute: guessing the token is slow here too
  EXPECT_EQ(PostVisit(body, kToken).result_int(), 429u);
  EXPECT_EQ(PostWorld(R"({"world":"dinosaur"})", kToken).result_int(), 429u);
  EXPECT_EQ(visits_, 0);
}

TEST_F(WebServerTest, AnotherSitesPageMayNotActEvenWithTheToken) {
  Start();
  const std::string body = R"({"world":"dinosaur"})";
  EXPECT_EQ(Request(http::verb::post, "/api/world", body,
                    {{"Content-Type", "application/json"}, {"Authorization", std::string("Bearer ") + kToken},
                     {"Origin", "http://evil.example"}})
                .result_int(),
            403u);
  EXPECT_EQ(actions_, 0);
  EXPECT_EQ(Request(http::verb::post, "/api/world", body,
                    {{"Content-Type", "application/json"}, {"Authorization", std::string("Bearer ") + kToken},
                     {"Origin", "http://127.0.0.1:" + std::to_string(server_->port())}})
                .result_int(),
            202u);  // the console's own page
  EXPECT_EQ(actions_, 1);
}

TEST_F(WebServerTest, ActionsAreRateLimitedRefusedOnesIncluded) {
  Start();
  int limited = 0;
  for (int i = 0; i < 8; ++i) limited += PostWorld(R"({"world":"dinosaur"})", "0123456789abcdef-guess").result_int() == 429u;
  EXPECT_EQ(limited, 3);  // a burst of 5, then 12 a minute
  const auto refused = PostWorld(R"({"world":"dinosaur"})", kToken);
  EXPECT_EQ(refused.result_int(), 429u);
  EXPECT_EQ(refused[http::field::retry_after], "5");  // a script knows how long to wait
  EXPECT_EQ(actions_, 0);
}

TEST_F(WebServerTest, PollingFasterThanTheRequestsRateIsToldWhenToAskAgain) {
  Start();
  // 20 requests a second with a burst of 40: 100 GETs back to back run out of tokens unless
  // they take 3 s.
  http::response<http::string_body> last;
  int refused = 0;
  for (int i = 0; i < 100; ++i) {
    auto res = Request(http::verb::get, "/api/state");
    if (res.result_int() == 429u) {
      ++refused;
      last = std::move(res);
    }
  }
  EXPECT_GT(refused, 0);
  EXPECT_EQ(last[http::field::retry_after], "1");
  EXPECT_EQ(last.body(), R"({"error":"too many requests"})");
}

TEST_F(WebServerTest, WithoutATokenActionsAreOff) {
  Start("");
  EXPECT_EQ(PostWorld(R"({"world":"dinosaur"})", kToken).result_int(), 403u);
  EXPECT_EQ(actions_, 0);
}

TEST_F(WebServerTest, AnOversizedBodyGets413AndChangesNothing) {
  Start();
  const auto res = PostWorld(R"({"world":")" + std::string(5000, 'a') + "\"}", kToken);
  EXPECT_EQ(res.result_int(), 413u);
  EXPECT_EQ(actions_, 0);
}

struct WsClient {
  explicit WsClient(std::uint16_t port) : ws(ioc) {
    tcp::socket& s = ws.next_layer();
    s.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port));
    ws.handshake("127.0.0.1:" + std::to_string(port), "/ws");
  }
  std::string Read() {
    beast::flat_buffer b;
    ws.read(b);
    return beast::buffers_to_string(b.data());
  }
  net::io_context ioc;
  websocket::stream<tcp::socket> ws;
};

TEST_F(WebServerTest, ViewersGetTheStateThenEveryBroadcast) {
  Start();
  WsClient viewer(server_->port());
  EXPECT_EQ(viewer.Read(), R"({"type":"state"})");
  server_->Broadcast(R"({"n":1})");
  EXPECT_EQ(viewer.Read(), R"({"n":1})");
  EXPECT_EQ(server_->counts().viewers, 1u);
}

TEST_F(WebServerTest, AViewerThatSendsAnythingIsClosed) {
  Start();
  WsClient viewer(server_->port());
  viewer.Read();
  viewer.ws.write(net::buffer(std::string("hello")));
  beast::flat_buffer b;
  beast::error_code ec;
  viewer.ws.read(b, ec);
  EXPECT_EQ(ec, websocket::error::closed);
  EXPECT_EQ(viewer.ws.reason().code, websocket::close_code::policy_error);
}

TEST_F(WebServerTest, AViewerThatStopsReadingIsDroppedAndTheOthersGoOn) {
  Start();
  WsClient slow(server_->port());
  WsClient fast(server_->port());
  slow.Read();
  fast.Read();
  // 1 MB states: the slow viewer's socket buffers fill after a few, then its queue.
  const std::string big(1 << 20, 'x');
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  int sent = 0;
  while (server_->counts().viewers_dropped == 0 && std::chrono::steady_clock::now() < deadline) {
    server_->Broadcast(big);
    ++sent;
    EXPECT_EQ(fast.Read().size(), big.size());  // the fast one keeps up, state after state
  }
  EXPECT_EQ(server_->counts().viewers_dropped, 1u) << "after " << sent << " states";
  server_->Broadcast("after");
  EXPECT_EQ(fast.Read(), "after");
  EXPECT_EQ(server_->counts().viewers, 1u);
}

}  // namespace
}  // namespace handshare::web_console
