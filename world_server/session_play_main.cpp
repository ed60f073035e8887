// session_play: republishes a recording (session_record) with its original timing.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "handshare/node/node_main.hpp"
#include "handshare/world_server/recording.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "session_play FILE", "Republishes a recording of session_record into a session with its original timing "
                           "(relative to its first sample) scaled by 1/--speed; scene state, message board and "
                           "deformations stay transient-local for late joiners. It announces itself as member "
                           "'player' (kind world_server, device 'replay').");
  handshare::node::DeclareSessionOptions(options);
  options.Value("speed", "X", "play X times as fast as recorded", "1")
      .Value("wait-for-readers", "N", "start the clock once N spectators matched the scene-state and deformation writers", "0")
      .Value("deliver-timeout", "SEC",
             "after the last sample, wait at most this long for every matched reader to acknowledge the scene, "
             "board, deformations and control events",
             "10")
      .Value("hold", "SEC", "then stay this long (late joiners)", "1")
      .Flag("check", "only read and deserialize every sample (no DDS); exit 0 if the recording is sound");
  // Options knows only --name arguments; FILE is the one positional argument.
  std::vector<const char*> rest{argv[0]};
  std::vector<std::string> files;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--", 0) == 0) {
      rest.push_back(argv[i]);
      if (arg.find('=') == std::string::npos && arg != "--check" && arg != "--help" && i + 1 < argc) {
        rest.push_back(argv[++i]);
      }
    } else {
      files.push_back(arg);
    }
  }
  if (files.size() == 1 && std::find(rest.begin(), rest.end(), std::string("--check")) != rest.end()) {
    // --check needs no session: verify without DDS.
    try {
      const auto n = handshare::server::VerifyRecording(files[0]);
      std::printf("%s: %lld samples, all sound\n", files[0].c_str(), static_cast<long long>(n));
      return 0;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "session_play: error: %s\n", e.what());
      return 1;
    }
  }
  return handshare::node::RunNodeMain(static_cast<int>(rest.size()), rest.data(), options, [&](const auto& o) {
    if (files.size() != 1) {
      throw handshare::common::OptionError(files.empty() ? "missing the recording FILE"
                                                         : "expected one FILE, got " + std::to_string(files.size()));
    }
    handshare::server::PlayConfig config;
    config.where = handshare::node::ReadSessionOptions(o);
    config.file = files[0];
    config.speed = o.GetDouble("speed", 0.01, 1000.0);
    config.wait_for_readers = static_cast<int>(o.GetInt("wait-for-readers", 0, 1000));
    config.deliver_timeout = std::chrono::duration<double>(o.GetDouble("deliver-timeout", 0.0, 1e6));
    config.hold = std::chrono::duration<double>(o.GetDouble("hold", 0.0, 1e6));
    return handshare::server::RunPlayer(config);
  });
}
