#include "handshare/speech/playback.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <numbers>
#include <vector>

namespace handshare::speech {
namespace {

using Clock = std::chrono::steady_clock;

std::vector<std::int16_t> Beep(double duration_s, int rate_hz) {
  std::vector<std::int16_t> samples(static_cast<std::size_t>(duration_s * rate_hz));
  for (std::size_t i = 0; i < samples.size(); ++i) {
    samples[i] = static_cast<std::int16_t>(3000.0 * std::sin(2.0 * std::numbers::pi * 440.0 * i / rate_hz));
  }
  return samples;
}

TEST(SpeechPlayback, NullDeviceAcceptsTheWholeClip) {
  // ALSA's "null" PCM (defined in alsa-lib's own configuration) needs no sound card.
  const PlaybackStatus status = Play(Beep(0.2, 22050), 22050, "null");
  EXPECT_TRUE(status.ok()) << status.message;
  EXPECT_TRUE(status.message.empty());
}

TEST(SpeechPlayback, MissingDeviceReturnsAClearStatusQuickly) {
  const auto start = Clock::now();
  const PlaybackStatus status = Play(Beep(0.2, 22050), 22050, "handshare_no_such_device");
  EXPECT_EQ(status.code, PlaybackStatus::Code::kNoDevice);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.message.find("handshare_no_such_device"), std::string::npos) << status.message;
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(2));
}

TEST(SpeechPlayback, DefaultDeviceEitherPlaysOrSaysWhyWithoutHanging) {
  // This machine may or may not have a sound card; both outcomes are fine, hanging is not.
  const auto start = Clock::now();
  const PlaybackStatus status = Play(Beep(0.1, 22050), 22050);
  if (status.ok()) {
    EXPECT_TRUE(status.message.empty());
  } else {
    EXPECT_NE(status.message.find("'default'"), std::string::npos) << status.message;
  }
  // 0.1 s of audio plus the 3 s safety margin of the deadline.
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(4));
}

TEST(SpeechPlayback, BadArgumentsAreRejectedBeforeTouchingTheDevice) {
  const PlaybackStatus status = Play(Beep(0.1, 22050), 0, "handshare_no_such_device");
  EXPECT_EQ(status.code, PlaybackStatus::Code::kInvalidArgument);
  EXPECT_NE(status.message.find("sample_rate_hz"), std::string::npos) << status.message;
  // Nothing to play: success without opening (so even a missing device is fine).
  EXPECT_TRUE(Play({}, 22050, "handshare_no_such_device").ok());
}

}  // namespace
}  // namespace handshare::speech
