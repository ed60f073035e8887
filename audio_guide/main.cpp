// audio_guide: speaks the session's message board.
#include "handshare/audio_guide/guide.hpp"
#include "handshare/common/node_main.hpp"

int main(int argc, char** argv) {
  handshare::common::Options options(
      "audio_guide", "Speaks every message-board text of a handshare session with eSpeak NG.");
  options.Value("domain", "D", "DDS domain id (0..232)", "0")
      .Value("session", "S", "session name", std::nullopt, true)
      .Value("name", "NAME", "member name (default audio-<pid>)", "")
      .Value("out", "DIR", "write one WAV (and a .txt) per message here instead of playing", "")
      .Value("alsa-device", "PCM", "ALSA device to play on", "default")
      .Value("duration", "SEC", "run this long, then end (0: until SIGINT/SIGTERM)", "0")
      .Value("qos", "FILE", "QoS profile XML (default: deploy/qos/handshare_qos.xml)", "");
  return handshare::common::RunNodeMain(argc, argv, options, [](const auto& o) {
    handshare::audio_guide::GuideConfig c;
    c.domain_id = static_cast<int>(o.GetInt("domain", 0, 232));
    c.session = o.GetString("session");
    c.name = o.GetString("name");
    c.out_dir = o.GetString("out");
    c.alsa_device = o.GetString("alsa-device");
    c.duration = std::chrono::duration<double>(o.GetDouble("duration", 0.0, 1e7));
    c.qos_file = o.GetString("qos");
    return handshare::audio_guide::Guide(c).Run();
  });
}
