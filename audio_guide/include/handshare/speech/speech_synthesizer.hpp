#pragma once
/// @file
/// Text to speech with eSpeak NG (libespeak-ng), rendered into memory.

#include <string>
#include <string_view>
#include <vector>

#include "handshare/speech/audio_clip.hpp"

namespace handshare::speech {

/// The result of one synthesis.
struct Utterance {
  AudioClip audio;        ///< mono int16 at eSpeak's native rate (22050 Hz with Debian's data).
  std::string language;   ///< the language actually spoken ("en" after a fallback).
  std::string warning;    ///< empty, or why the requested language was not used.
};

/// Speaks text into memory. eSpeak NG is a process-wide singleton with global state; every
/// instance shares it, and all calls are serialized by one process-wide mutex, so instances may
/// be used from any thread (calls simply wait for each other). Not real-time safe.
class SpeechSynthesizer {
 public:
  /// Initializes eSpeak NG on first use in the process (synchronous mode, no audio device).
  /// Throws std::runtime_error if its data cannot be found or loaded.
  SpeechSynthesizer();

  /// Synthesizes UTF-8 `text` with the voice for `language` (an eSpeak language name such as
  /// "en", "en-us", "ja"). If no such voice exists, speaks English instead and reports it in
  /// Utterance::warning (and once per language on std::clog).
  /// Empty text, or text of only whitespace, gives an Utterance with no samples (the rate is still
  /// set); this is not an error. Throws std::runtime_error if eSpeak fails.
  [[nodiscard]] Utterance Synthesize(std::string_view text, std::string_view language);

  /// eSpeak's output rate [Hz].
  [[nodiscard]] int sample_rate_hz() const noexcept { return sample_rate_hz_; }

  /// True if eSpeak has a voice for `language`.
  [[nodiscard]] bool HasLanguage(std::string_view language) const;

 private:
  int sample_rate_hz_ = 0;
};

}  // namespace handshare::speech
