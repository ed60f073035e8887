#pragma once
/// @file
/// Short sound cues of the audio guide: a button's click, a lever's detent, a page turned, a
/// world changed; and which change of a control's shared state sounds like which.

#include <cstdint>
#include <map>
#include <optional>
#include <string>

#include "handshare/speech/audio_clip.hpp"

namespace handshare::speech {

enum class Cue { kButtonClick, kLeverDetent, kPageTurn, kWorldChange };

/// "click", "detent", "page", "world".
[[nodiscard]] const char* CueName(Cue cue) noexcept;

/// The cue as mono samples at `sample_rate_hz` (8000..192000, else std::invalid_argument):
/// click: a 12 ms decaying 2.5 kHz tick with a noise transient; detent: two soft 1.2 kHz ticks
/// 60 ms apart; page: a 250 ms rising and falling band of noise (a swish); world: a two-note
/// chime, 660 Hz then 880 Hz, 0.6 s. Peak about a quarter of full scale.
[[nodiscard]] AudioClip SynthesizeCue(Cue cue, int sample_rate_hz);

/// A control's shared state (msg::ControlState without the middleware): lever: index = detent,
/// engaged false; book: engaged = open, index = page (-1 closed); button, arrow: engaged =
/// pressed, index -1.
struct ControlSnapshot {
  std::string scene;
  std::int32_t index = -1;
  bool engaged = false;
  std::uint32_t changes = 0;
};

/// Turns the stream of control states and world names into cues. A control seen for the first
/// time (or first in its world) makes no sound: a guide that joins late does not click for
/// every control it learns about; nor does a repeated state.
class CueWatch {
 public:
  /// A control's new state: a button or arrow pressed clicks, a lever in another detent
  /// clicks softly, a book opened or at another page swishes.
  std::optional<Cue> OnControl(const std::string& control_id, const ControlSnapshot& now);
  /// The world shown: another world than the last one chimes (not the first one seen; a new
  /// revision of the same world, a gravity change, is silent). Forgets the other worlds' controls.
  std::optional<Cue> OnWorld(const std::string& scene);

 private:
  std::map<std::string, ControlSnapshot> controls_;
  std::string world_;
};

}  // namespace handshare::speech
