#pragma once
/// The audio guide node: speaks every new message-board text (and its next action) with
/// eSpeak NG, to the sound device or, with an output folder, into one WAV file per message.
#include <chrono>
#include <string>

#include "handshare/common/node_main.hpp"

namespace handshare::audio_guide {

struct GuideConfig {
  common::SessionOptions where;  // domain, session, duration, QoS file
  std::string name;                              // member name; "" = audio-<pid>
  std::string out_dir;                           // "" = play on alsa_device
  std::string alsa_device = "default";
  double rejoin_after_s = 15.0;                  // no board from the world server this long after joining: join again; 0: never
};

class Guide {
 public:
  explicit Guide(GuideConfig config);
  int Run();

 private:
  GuideConfig config_;
};

}  // namespace handshare::audio_guide
