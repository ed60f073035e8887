// web_console: a session's operator console in a browser (HTTP and WebSocket).
#include "handshare/node/node_main.hpp"
#include "handshare/web_console/console.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "web_console",
      "Serves a handshare session's operator console to browsers: every station's loop, the world "
      "server's tick, the world and the message board, live; an operator with the token sends the "
      "session to another world. Listens on localhost unless told otherwise.");
  handshare::node::DeclareSessionOptions(options);
  options.Value("name", "NAME", "member name, and the user of the console's control events", "web-console")
      .Value("listen", "ADDR:PORT", "where browsers connect (0.0.0.0:PORT: every interface; [::1]:PORT: IPv6)",
             "127.0.0.1:8080")
      .Value("token-file", "FILE", "the operator's token (16 to 256 printable characters); without it, actions are off", "")
      .Value("tls-cert", "PEM", "certificate chain: HTTPS and WSS only (with --tls-key)", "")
      .Value("tls-key", "PEM", "private key of --tls-cert", "")
      .Value("www", "DIR", "the pages' folder (default: installed share/handshare/www, or the source tree's)", "")
      .Value("max-connections", "N", "browsers' connections at once, HTTP and WebSocket (more are closed)", "64");
  return handshare::node::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::web_console::ConsoleConfig c;
    c.where = handshare::node::ReadSessionOptions(o);
    c.name = o.GetString("name");
    c.listen = o.GetString("listen");
    c.token_file = o.GetString("token-file");
    c.tls_cert = o.GetString("tls-cert");
    c.tls_key = o.GetString("tls-key");
    c.www_dir = o.GetString("www");
    c.max_connections = static_cast<std::size_t>(o.GetInt("max-connections", 1, 10000));
    return handshare::web_console::Console(c).Run();
  });
}
