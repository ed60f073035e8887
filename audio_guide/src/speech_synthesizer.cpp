#include "handshare/speech/speech_synthesizer.hpp"

#include <espeak-ng/speak_lib.h>

#include <algorithm>
#include <cctype>
#include <iostream>
#include <mutex>
#include <set>
#include <stdexcept>

namespace handshare::speech {

namespace {

// eSpeak NG keeps its state in globals: one mutex guards every call into it and the variables
// below. The synthesis callback runs on the calling thread (synchronous mode), under the lock.
std::mutex g_espeak_mutex;
int g_sample_rate_hz = 0;                 // 0 until initialized
std::vector<std::int16_t>* g_sink = nullptr;  // where the callback appends samples
std::set<std::string, std::less<>> g_warned_languages;

int CollectSamples(short* samples, int count, espeak_EVENT* /*events*/) {
  if (samples != nullptr && count > 0 && g_sink != nullptr) {
    g_sink->insert(g_sink->end(), samples, samples + count);
  }
  return 0;  // continue synthesis
}

// Call with g_espeak_mutex held.
void EnsureInitialized() {
  if (g_sample_rate_hz > 0) return;
  // Synchronous: audio comes back through the callback, no sound device is touched.
  // DONT_EXIT: report a missing data directory instead of calling exit().
  const int rate_hz = espeak_Initialize(AUDIO_OUTPUT_SYNCHRONOUS, 0, nullptr, espeakINITIALIZE_DONT_EXIT);
  if (rate_hz <= 0) {
    throw std::runtime_error(
        "SpeechSynthesizer: espeak_Initialize failed (is the espeak-ng-data package installed?)");
  }
  espeak_SetSynthCallback(CollectSamples);
  g_sample_rate_hz = rate_hz;
}

// Voices eSpeak can speak without external data: MBROLA voices ("mb/...") need the separate
// mbrola program and its databases, which handshare does not install.
bool IsBuiltinVoice(const espeak_VOICE& voice) {
  return voice.identifier != nullptr && std::string_view(voice.identifier).rfind("mb/", 0) != 0;
}

// Call with g_espeak_mutex held.
bool HasLanguageLocked(std::string_view language) {
  const espeak_VOICE** voices = espeak_ListVoices(nullptr);
  for (; voices != nullptr && *voices != nullptr; ++voices) {
    const espeak_VOICE& voice = **voices;
    if (!IsBuiltinVoice(voice) || voice.languages == nullptr) continue;
    // languages: repeated [priority byte][NUL-terminated name], ended by a zero byte.
    for (const char* p = voice.languages; *p != 0;) {
      ++p;  // priority
      const std::string_view name(p);
      if (name.size() == language.size() &&
          std::equal(name.begin(), name.end(), language.begin(), [](char a, char b) {
            return std::tolower(static_cast<unsigned char>(a)) == std::tolower(static_cast<unsigned char>(b));
          })) {
        return true;
      }
      p += name.size() + 1;
    }
  }
  return false;
}

bool IsBlank(std::string_view text) {
  return std::all_of(text.begin(), text.end(),
                     [](char c) { return std::isspace(static_cast<unsigned char>(c)) != 0; });
}

}  // namespace

SpeechSynthesizer::SpeechSynthesizer() {
  std::lock_guard lock(g_espeak_mutex);
  EnsureInitialized();
  sample_rate_hz_ = g_sample_rate_hz;
}

bool SpeechSynthesizer::HasLanguage(std::string_view language) const {
  std::lock_guard lock(g_espeak_mutex);
  return HasLanguageLocked(language);
}

Utterance SpeechSynthesizer::Synthesize(std::string_view text, std::string_view language) {
  std::lock_guard lock(g_espeak_mutex);
  Utterance result;
  result.audio.sample_rate_hz = sample_rate_hz_;
  result.language = std::string(language);
  if (!HasLanguageLocked(language) || espeak_SetVoiceByName(result.language.c_str()) != EE_OK) {
    result.warning = "no eSpeak NG voice for language '" + result.language + "'; speaking English";
    if (g_warned_languages.insert(result.language).second) {
      std::clog << "handshare::speech: " << result.warning << '\n';
    }
    result.language = "en";
    if (espeak_SetVoiceByName("en") != EE_OK) {
      throw std::runtime_error("SpeechSynthesizer: eSpeak NG has no English voice either");
    }
  }
  if (IsBlank(text)) return result;

  const std::string terminated(text);  // eSpeak wants a NUL-terminated buffer
  g_sink = &result.audio.samples;
  const espeak_ERROR status = espeak_Synth(terminated.c_str(), terminated.size() + 1, 0, POS_CHARACTER,
                                           0, espeakCHARS_UTF8, nullptr, nullptr);
  const espeak_ERROR sync_status = espeak_Synchronize();
  g_sink = nullptr;
  if (status != EE_OK || sync_status != EE_OK) {
    throw std::runtime_error("SpeechSynthesizer: espeak_Synth failed with status " +
                             std::to_string(status != EE_OK ? status : sync_status) +
                             " for text of " + std::to_string(text.size()) + " bytes");
  }
  return result;
}

}  // namespace handshare::speech
