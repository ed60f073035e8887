// audio_guide: speaks the session's message board.
#include "handshare/audio_guide/guide.hpp"
#include "handshare/node/node_main.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "audio_guide", "Speaks every message-board text of a handshare session with eSpeak NG.");
  handshare::node::DeclareSessionOptions(options);
  options.Value("name", "NAME", "member name (default audio-<pid>)", "")
      .Value("out", "DIR", "write one WAV (and a .txt) per message here instead of playing", "")
      .Value("alsa-device", "PCM", "ALSA device to play on", "default")
      .Value("language", "en|ja", "the board's language to speak (ja: from the scene's kana reading)", "en")
      .Value("cues", "on|off", "sound cues: a button's click, a lever's detent, a page turned, a world changed", "on")
      .Value("rejoin-after", "SEC",
             "join again with a new participant when no board came from the world server this long after "
             "joining (a secured join whose handshake never finished; 0: never)", "15");
  return handshare::node::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::audio_guide::GuideConfig c;
    c.where = handshare::node::ReadSessionOptions(o);
    c.name = o.GetString("name");
    c.out_dir = o.GetString("out");
    c.alsa_device = o.GetString("alsa-device");
    c.language = o.GetChoice("language", {"en", "ja"});
    c.cues = o.GetChoice("cues", {"on", "off"}) == "on";
    c.rejoin_after_s = o.GetDouble("rejoin-after", 0.0, 3600.0);
    return handshare::audio_guide::Guide(c).Run();
  });
}
