#pragma once
/// The audio guide node: speaks every new message-board text (and its next action) in one
/// language with eSpeak NG, to the sound device or, with an output folder, into one WAV file per
/// message. Japanese is spoken from the board's kana reading (the ja voice cannot read kanji). Short
/// sound cues mark a button's click, a lever's detent, a page turned and a world changed.
#include <chrono>
#include <string>

#include "handshare/common/session_options.hpp"

namespace handshare::audio_guide {

struct GuideConfig {
  common::SessionOptions where;  // domain, session, duration, QoS file
  std::string name;                              // member name; "" = audio-<pid>
  std::string out_dir;                           // "" = play on alsa_device
  std::string alsa_device = "default";
  bool cues = true;                              // sound cues: click, detent, page turn, world change
  std::string language = "en";                   // the board's language spoken: en, or ja (its kana reading)
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
