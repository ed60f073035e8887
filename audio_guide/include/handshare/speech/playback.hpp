#pragma once
/// @file
/// Playing audio on a sound device (ALSA).

#include <cstdint>
#include <span>
#include <string>

namespace handshare::speech {

/// Outcome of Play(). Never an exception: a missing sound card is an expected condition for a
/// spectator node (it then just shows the caption).
struct PlaybackStatus {
  enum class Code {
    kOk,               ///< all samples were played.
    kNoDevice,         ///< the device could not be opened (no sound card, busy, unknown name).
    kInvalidArgument,  ///< sample_rate_hz <= 0.
    kDeviceError,      ///< the device was opened but configuring or writing failed.
  };
  Code code = Code::kOk;
  std::string message;  ///< what failed, with the device name and ALSA's reason; empty if kOk.

  [[nodiscard]] bool ok() const noexcept { return code == Code::kOk; }
};

/// Plays mono int16 `samples` at `sample_rate_hz` on the ALSA PCM `device` ("default" follows
/// the system's configuration; "null" discards) and blocks until they have been played.
/// An empty span returns kOk without opening the device. The device is opened non-blocking, so a
/// missing or busy device returns kNoDevice at once instead of waiting. ALSA's own error
/// printing to stderr is silenced process-wide on first use (the reason is in `message`).
[[nodiscard]] PlaybackStatus Play(std::span<const std::int16_t> samples, int sample_rate_hz,
                                  const std::string& device = "default") noexcept;

}  // namespace handshare::speech
