#pragma once
// Frame-based measures that tell speech from silence, tones and noise, for the tests.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include "handshare/speech/audio_clip.hpp"

namespace handshare::speech::test {

struct FrameStats {
  double rms;                  // of the int16 values
  double zero_crossings_per_s;
};

/// Splits the clip into consecutive frames of frame_s seconds (the tail is dropped).
inline std::vector<FrameStats> Frames(const AudioClip& clip, double frame_s) {
  const auto length = static_cast<std::size_t>(frame_s * clip.sample_rate_hz);
  std::vector<FrameStats> frames;
  for (std::size_t start = 0; length > 1 && start + length <= clip.samples.size(); start += length) {
    double energy = 0.0;
    int crossings = 0;
    for (std::size_t i = start; i < start + length; ++i) {
      energy += static_cast<double>(clip.samples[i]) * clip.samples[i];
      if (i > start && (clip.samples[i] >= 0) != (clip.samples[i - 1] >= 0)) ++crossings;
    }
    frames.push_back({std::sqrt(energy / static_cast<double>(length)), crossings / frame_s});
  }
  return frames;
}

inline double Rms(const AudioClip& clip) {
  double energy = 0.0;
  for (const std::int16_t s : clip.samples) energy += static_cast<double>(s) * s;
  return clip.samples.empty() ? 0.0 : std::sqrt(energy / static_cast<double>(clip.samples.size()));
}

/// The clip without its leading and trailing near-silence (|sample| below 2 % of the peak).
inline AudioClip TrimSilence(const AudioClip& clip) {
  int peak = 0;
  for (const std::int16_t v : clip.samples) peak = std::max(peak, std::abs(static_cast<int>(v)));
  const int threshold = peak / 50;
  std::size_t first = 0;
  std::size_t last = clip.samples.size();
  while (first < last && std::abs(static_cast<int>(clip.samples[first])) <= threshold) ++first;
  while (last > first && std::abs(static_cast<int>(clip.samples[last - 1])) <= threshold) --last;
  return {std::vector<std::int16_t>(clip.samples.begin() + static_cast<std::ptrdiff_t>(first),
                                    clip.samples.begin() + static_cast<std::ptrdiff_t>(last)),
          clip.sample_rate_hz};
}

/// What makes a clip look like speech:
///  - loud frames: RMS above 25 % of the loudest 10 ms frame;
///  - pauses: runs of quiet frames (RMS below 5 % of the loudest) strictly inside the utterance,
///    that is between two loud frames (gaps between words and before plosives);
///  - voiced frames: loud, with 300..4000 zero crossings per second (a periodic glottal source
///    under formants); fricatives: some energy (above 5 %) and more than 5000 crossings per
///    second ("s" in "solar", "system").
struct SpeechProfile {
  int loud_frames = 0;
  int inner_pauses = 0;
  int voiced_frames = 0;
  int fricative_frames = 0;
};

inline SpeechProfile Profile(const AudioClip& clip) {
  const std::vector<FrameStats> frames = Frames(clip, 0.010);
  SpeechProfile profile;
  double loudest = 0.0;
  for (const auto& f : frames) loudest = std::max(loudest, f.rms);
  if (loudest <= 0.0) return profile;
  int first_loud = -1;
  int last_loud = -1;
  for (int i = 0; i < static_cast<int>(frames.size()); ++i) {
    const auto& f = frames[static_cast<std::size_t>(i)];
    if (f.rms > 0.25 * loudest) {
      ++profile.loud_frames;
      if (first_loud < 0) first_loud = i;
      last_loud = i;
      if (f.zero_crossings_per_s >= 300.0 && f.zero_crossings_per_s <= 4000.0) ++profile.voiced_frames;
    }
    if (f.rms > 0.05 * loudest && f.zero_crossings_per_s > 5000.0) ++profile.fricative_frames;
  }
  bool in_pause = false;
  for (int i = first_loud; i >= 0 && i <= last_loud; ++i) {
    const bool quiet = frames[static_cast<std::size_t>(i)].rms < 0.05 * loudest;
    if (quiet && !in_pause) ++profile.inner_pauses;
    in_pause = quiet;
  }
  return profile;
}

}  // namespace handshare::speech::test
