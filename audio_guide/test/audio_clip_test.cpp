#include "handshare/speech/audio_clip.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <string>

namespace handshare::speech {
namespace {

std::filesystem::path TempPath(const std::string& name) {
  return std::filesystem::path(::testing::TempDir()) /
         ("handshare_speech_" + std::to_string(::getpid()) + "_" + name);
}

std::string FileBytes(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  std::string bytes;
  char c;
  while (file.get(c)) bytes.push_back(c);
  return bytes;
}

std::uint32_t LittleEndian32(const std::string& bytes, std::size_t at) {
  return static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at])) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + 1])) << 8U |
         static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + 2])) << 16U |
         static_cast<std::uint32_t>(static_cast<unsigned char>(bytes[at + 3])) << 24U;
}

TEST(SpeechWav, RoundTripIsExact) {
  std::vector<std::int16_t> samples(12345);
  std::mt19937 rng(99);
  std::uniform_int_distribution<int> value(std::numeric_limits<std::int16_t>::min(),
                                           std::numeric_limits<std::int16_t>::max());
  for (auto& s : samples) s = static_cast<std::int16_t>(value(rng));
  samples[0] = std::numeric_limits<std::int16_t>::min();
  samples[1] = std::numeric_limits<std::int16_t>::max();
  const auto path = TempPath("roundtrip.wav");
  WriteWav(path, samples, 22050);
  const AudioClip back = ReadWav(path);
  EXPECT_EQ(back.sample_rate_hz, 22050);
  EXPECT_EQ(back.samples, samples);
  EXPECT_NEAR(back.duration_s(), 12345.0 / 22050.0, 1e-12);
  std::filesystem::remove(path);
}

TEST(SpeechWav, HeaderIsCanonical16BitMonoPcm) {
  const std::vector<std::int16_t> samples = {1, -2, 0x1234};
  const auto path = TempPath("header.wav");
  WriteWav(path, samples, 16000);
  const std::string bytes = FileBytes(path);
  std::filesystem::remove(path);
  ASSERT_EQ(bytes.size(), 44U + 2U * samples.size());
  EXPECT_EQ(bytes.substr(0, 4), "RIFF");
  EXPECT_EQ(LittleEndian32(bytes, 4), bytes.size() - 8);
  EXPECT_EQ(bytes.substr(8, 8), "WAVEfmt ");
  EXPECT_EQ(LittleEndian32(bytes, 16), 16U);           // fmt chunk size
  EXPECT_EQ(LittleEndian32(bytes, 20), 1U | 1U << 16);  // PCM, 1 channel
  EXPECT_EQ(LittleEndian32(bytes, 24), 16000U);        // sample rate
  EXPECT_EQ(LittleEndian32(bytes, 28), 32000U);        // byte rate
  EXPECT_EQ(LittleEndian32(bytes, 32), 2U | 16U << 16);  // block align, bits per sample
  EXPECT_EQ(bytes.substr(36, 4), "data");
  EXPECT_EQ(LittleEndian32(bytes, 40), 6U);
  EXPECT_EQ(static_cast<unsigned char>(bytes[48]), 0x34);  // little-endian sample data
  EXPECT_EQ(static_cast<unsigned char>(bytes[49]), 0x12);
}

TEST(SpeechWav, ReaderSkipsUnknownChunks) {
  // A LIST chunk (odd size, padded) between fmt and data, as other tools write.
  const auto path = TempPath("list.wav");
  std::string bytes = "RIFF____WAVEfmt ";
  const auto put32 = [&bytes](std::uint32_t v) {
    for (int k = 0; k < 4; ++k) bytes.push_back(static_cast<char>((v >> (8 * k)) & 0xFFU));
  };
  put32(16);
  put32(1U | 1U << 16);
  put32(8000);
  put32(16000);
  put32(2U | 16U << 16);
  bytes += "LIST";
  put32(3);
  bytes += "abc";
  bytes.push_back('\0');  // pad byte
  bytes += "data";
  put32(4);
  bytes += std::string("\x01\x00\xFF\xFF", 4);
  const std::uint32_t riff_size = static_cast<std::uint32_t>(bytes.size() - 8);
  for (int k = 0; k < 4; ++k) bytes[4 + static_cast<std::size_t>(k)] = static_cast<char>((riff_size >> (8 * k)) & 0xFFU);
  std::ofstream(path, std::ios::binary) << bytes;
  const AudioClip clip = ReadWav(path);
  std::filesystem::remove(path);
  EXPECT_EQ(clip.sample_rate_hz, 8000);
  EXPECT_EQ(clip.samples, (std::vector<std::int16_t>{1, -1}));
}

TEST(SpeechWav, EmptyClipRoundTrips) {
  const auto path = TempPath("empty.wav");
  WriteWav(path, {}, 22050);
  const AudioClip clip = ReadWav(path);
  std::filesystem::remove(path);
  EXPECT_TRUE(clip.samples.empty());
  EXPECT_EQ(clip.sample_rate_hz, 22050);
  EXPECT_EQ(clip.duration_s(), 0.0);
}

void ExpectRuntimeErrorMentioning(const std::function<void()>& action, const std::string& needle) {
  try {
    action();
    ADD_FAILURE() << "expected std::runtime_error mentioning " << needle;
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
  }
}

TEST(SpeechWav, BadPathsAndBadFilesGiveClearErrors) {
  const std::filesystem::path missing = "/nonexistent_handshare_dir/clip.wav";
  const std::vector<std::int16_t> samples = {1, 2, 3};
  ExpectRuntimeErrorMentioning([&] { WriteWav(missing, samples, 22050); }, missing.string());
  ExpectRuntimeErrorMentioning([&] { WriteWav(missing, samples, 22050); }, "No such file or directory");
  ExpectRuntimeErrorMentioning([&] { (void)ReadWav(missing); }, missing.string());

  const auto text = TempPath("text.wav");
  std::ofstream(text) << "not a wave file at all";
  ExpectRuntimeErrorMentioning([&] { (void)ReadWav(text); }, "not a RIFF/WAVE file");

  // A stereo file: rejected with the reason.
  const auto stereo = TempPath("stereo.wav");
  WriteWav(stereo, samples, 22050);
  std::string bytes = FileBytes(stereo);
  bytes[22] = 2;  // channels
  std::ofstream(stereo, std::ios::binary) << bytes;
  ExpectRuntimeErrorMentioning([&] { (void)ReadWav(stereo); }, "16-bit mono");

  // A truncated file.
  WriteWav(stereo, samples, 22050);
  bytes = FileBytes(stereo);
  bytes.resize(bytes.size() - 2);
  std::ofstream(stereo, std::ios::binary | std::ios::trunc) << bytes;
  ExpectRuntimeErrorMentioning([&] { (void)ReadWav(stereo); }, "truncated");

  EXPECT_THROW(WriteWav(TempPath("rate.wav"), samples, 0), std::invalid_argument);
  std::filesystem::remove(text);
  std::filesystem::remove(stereo);
}

}  // namespace
}  // namespace handshare::speech
