#pragma once
/// @file
/// Mono 16-bit PCM audio and WAV file I/O.

#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

namespace handshare::speech {

/// Mono signed 16-bit PCM samples at a fixed rate.
struct AudioClip {
  std::vector<std::int16_t> samples;
  int sample_rate_hz = 0;

  /// Length of the clip [s]; 0 if empty or the rate is unset.
  [[nodiscard]] double duration_s() const noexcept {
    return sample_rate_hz > 0 ? static_cast<double>(samples.size()) / sample_rate_hz : 0.0;
  }
};

/// Writes a RIFF/WAVE file, PCM format 1, 16 bits, 1 channel, little-endian.
/// Throws std::invalid_argument if sample_rate_hz <= 0, std::runtime_error naming `path` and the
/// system's reason if the file cannot be written completely.
void WriteWav(const std::filesystem::path& path, std::span<const std::int16_t> samples,
              int sample_rate_hz);

/// Reads a WAV file written by WriteWav or any 16-bit mono PCM WAV (unknown chunks are skipped).
/// Throws std::runtime_error naming `path` and what is wrong (missing file, not RIFF/WAVE,
/// not 16-bit mono PCM, truncated data).
[[nodiscard]] AudioClip ReadWav(const std::filesystem::path& path);

}  // namespace handshare::speech
