// session_record: records every topic of a session, with its timing, into one file.
#include "handshare/node/node_main.hpp"
#include "handshare/world_server/recording.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "session_record", "Records every topic of a handshare session (samples with their receive times, disposes "
                        "and lost writers) into one SQLite file that is also a session log: play it with "
                        "session_play, read it with session_report.");
  handshare::node::DeclareSessionOptions(options);
  options.Value("out", "FILE", "the recording to create (must not exist)", std::nullopt, true);
  options.Value("rejoin-after", "SEC",
                "join again with a new participant when a member the world server has stays unheard this "
                "long (a secured join whose handshake never finished; 0: never)",
                "15");
  return handshare::node::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::server::RecordConfig config;
    config.where = handshare::node::ReadSessionOptions(o);
    config.out = o.GetString("out");
    config.rejoin_after = std::chrono::duration<double>(o.GetDouble("rejoin-after", 0.0, 3600.0));
    return handshare::server::RunRecorder(config);
  });
}
