#include "handshare/speech/playback.hpp"

#include <alsa/asoundlib.h>

#include <chrono>
#include <cstdarg>
#include <memory>
#include <mutex>
#include <thread>

namespace handshare::speech {

namespace {

using Clock = std::chrono::steady_clock;

// ALSA prints its own diagnostics to stderr (for example "cannot find card '0'" on every open
// without a sound card). The reason is returned in PlaybackStatus instead.
void QuietAlsaErrors(const char* /*file*/, int /*line*/, const char* /*function*/, int /*err*/,
                     const char* /*fmt*/, ...) {}

PlaybackStatus Failure(PlaybackStatus::Code code, const std::string& device, const char* what,
                       int error) {
  return {code, "ALSA device '" + device + "': " + what + ": " + snd_strerror(error)};
}

PlaybackStatus PlayOrFail(std::span<const std::int16_t> samples, int sample_rate_hz,
                          const std::string& device) {
  using Code = PlaybackStatus::Code;
  if (sample_rate_hz <= 0) {
    return {Code::kInvalidArgument, "Play: sample_rate_hz = " + std::to_string(sample_rate_hz) +
                                        " must be positive"};
  }
  if (samples.empty()) return {};
  static std::once_flag quiet_once;
  std::call_once(quiet_once, [] { snd_lib_error_set_handler(&QuietAlsaErrors); });

  // Non-blocking open: a busy or missing device fails now instead of waiting for it.
  snd_pcm_t* raw = nullptr;
  int error = snd_pcm_open(&raw, device.c_str(), SND_PCM_STREAM_PLAYBACK, SND_PCM_NONBLOCK);
  if (error < 0) return Failure(Code::kNoDevice, device, "cannot open for playback", error);
  const std::unique_ptr<snd_pcm_t, int (*)(snd_pcm_t*)> pcm(raw, &snd_pcm_close);

  constexpr unsigned kLatency_us = 200'000;
  error = snd_pcm_set_params(pcm.get(), SND_PCM_FORMAT_S16, SND_PCM_ACCESS_RW_INTERLEAVED, 1,
                             static_cast<unsigned>(sample_rate_hz), 1, kLatency_us);
  if (error < 0) {
    return Failure(Code::kDeviceError, device,
                   ("cannot set 16-bit mono at " + std::to_string(sample_rate_hz) + " Hz").c_str(), error);
  }

  // Stay non-blocking and poll with a deadline, so a device that stops consuming cannot hang
  // the caller: the clip's own length plus a generous margin.
  const auto clip = std::chrono::duration<double>(static_cast<double>(samples.size()) / sample_rate_hz);
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(clip) + std::chrono::seconds(3);
  const auto timed_out = [&] { return Clock::now() > deadline; };

  std::size_t written = 0;
  while (written < samples.size()) {
    const snd_pcm_sframes_t frames =
        snd_pcm_writei(pcm.get(), samples.data() + written, samples.size() - written);
    if (frames >= 0) {
      written += static_cast<std::size_t>(frames);
    } else if (frames == -EAGAIN) {
      snd_pcm_wait(pcm.get(), 50);
    } else {
      // Underrun (-EPIPE) or suspend (-ESTRPIPE): recover and go on.
      error = snd_pcm_recover(pcm.get(), static_cast<int>(frames), 1);
      if (error < 0) return Failure(Code::kDeviceError, device, "write failed", error);
    }
    if (timed_out()) {
      return {Code::kDeviceError, "ALSA device '" + device + "': timed out after writing " +
                                      std::to_string(written) + " of " +
                                      std::to_string(samples.size()) + " samples"};
    }
  }
  // Non-blocking drain starts draining and returns -EAGAIN; wait for the state to leave DRAINING.
  error = snd_pcm_drain(pcm.get());
  if (error < 0 && error != -EAGAIN) return Failure(Code::kDeviceError, device, "drain failed", error);
  while (snd_pcm_state(pcm.get()) == SND_PCM_STATE_DRAINING) {
    if (timed_out()) {
      return {Code::kDeviceError, "ALSA device '" + device + "': timed out while draining"};
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return {};
}

}  // namespace

PlaybackStatus Play(std::span<const std::int16_t> samples, int sample_rate_hz,
                    const std::string& device) noexcept {
  try {
    return PlayOrFail(samples, sample_rate_hz, device);
  } catch (...) {  // only std::bad_alloc from building messages can get here
    PlaybackStatus status;
    status.code = PlaybackStatus::Code::kDeviceError;
    return status;
  }
}

}  // namespace handshare::speech
