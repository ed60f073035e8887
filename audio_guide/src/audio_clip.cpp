#include "handshare/speech/audio_clip.hpp"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>
#include <stdexcept>
#include <string>

namespace handshare::speech {

namespace {

// RIFF is little-endian whatever the host is: write and read byte by byte.
void PutU16(std::string& out, std::uint16_t value) {
  out.push_back(static_cast<char>(value & 0xFFU));
  out.push_back(static_cast<char>((value >> 8U) & 0xFFU));
}

void PutU32(std::string& out, std::uint32_t value) {
  for (int shift = 0; shift < 32; shift += 8) out.push_back(static_cast<char>((value >> shift) & 0xFFU));
}

std::uint32_t GetU32(const std::string& in, std::size_t at) {
  std::uint32_t value = 0;
  for (int k = 3; k >= 0; --k) value = (value << 8U) | static_cast<unsigned char>(in[at + static_cast<std::size_t>(k)]);
  return value;
}

std::uint16_t GetU16(const std::string& in, std::size_t at) {
  return static_cast<std::uint16_t>(static_cast<unsigned char>(in[at]) |
                                    (static_cast<unsigned>(static_cast<unsigned char>(in[at + 1])) << 8U));
}

constexpr std::uint16_t kFormatPcm = 1;
constexpr std::uint16_t kChannels = 1;
constexpr std::uint16_t kBitsPerSample = 16;
constexpr std::size_t kHeaderBytes = 44;

}  // namespace

void WriteWav(const std::filesystem::path& path, std::span<const std::int16_t> samples,
              int sample_rate_hz) {
  if (sample_rate_hz <= 0) {
    throw std::invalid_argument("WriteWav(" + path.string() + "): sample_rate_hz = " +
                                std::to_string(sample_rate_hz) + " must be positive");
  }
  const std::size_t data_bytes = samples.size() * sizeof(std::int16_t);
  if (data_bytes > std::numeric_limits<std::uint32_t>::max() - kHeaderBytes) {
    throw std::invalid_argument("WriteWav(" + path.string() + "): " +
                                std::to_string(samples.size()) + " samples exceed the 4 GiB RIFF limit");
  }
  std::string bytes;
  bytes.reserve(kHeaderBytes + data_bytes);
  bytes += "RIFF";
  PutU32(bytes, static_cast<std::uint32_t>(36 + data_bytes));
  bytes += "WAVE";
  bytes += "fmt ";
  PutU32(bytes, 16);
  PutU16(bytes, kFormatPcm);
  PutU16(bytes, kChannels);
  PutU32(bytes, static_cast<std::uint32_t>(sample_rate_hz));
  PutU32(bytes, static_cast<std::uint32_t>(sample_rate_hz) * kChannels * kBitsPerSample / 8);  // byte rate
  PutU16(bytes, kChannels * kBitsPerSample / 8);                                               // block align
  PutU16(bytes, kBitsPerSample);
  bytes += "data";
  PutU32(bytes, static_cast<std::uint32_t>(data_bytes));
  for (const std::int16_t sample : samples) PutU16(bytes, static_cast<std::uint16_t>(sample));

  // stdio rather than ofstream: errno gives the reason (no such directory, permission, disk full).
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "wb"), &std::fclose);
  if (!file) {
    throw std::runtime_error("WriteWav(" + path.string() + "): cannot open: " + std::strerror(errno));
  }
  if (std::fwrite(bytes.data(), 1, bytes.size(), file.get()) != bytes.size() ||
      std::fflush(file.get()) != 0) {
    throw std::runtime_error("WriteWav(" + path.string() + "): write failed: " + std::strerror(errno));
  }
  if (std::fclose(file.release()) != 0) {
    throw std::runtime_error("WriteWav(" + path.string() + "): close failed: " + std::strerror(errno));
  }
}

AudioClip ReadWav(const std::filesystem::path& path) {
  const auto fail = [&path](const std::string& why) {
    return std::runtime_error("ReadWav(" + path.string() + "): " + why);
  };
  std::unique_ptr<std::FILE, int (*)(std::FILE*)> file(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!file) throw fail(std::string("cannot open: ") + std::strerror(errno));
  std::string bytes;
  char buffer[1 << 16];
  std::size_t got = 0;
  while ((got = std::fread(buffer, 1, sizeof buffer, file.get())) > 0) bytes.append(buffer, got);
  if (std::ferror(file.get()) != 0) throw fail(std::string("read failed: ") + std::strerror(errno));
  if (bytes.size() < 12 || bytes.compare(0, 4, "RIFF") != 0 || bytes.compare(8, 4, "WAVE") != 0) {
    throw fail("not a RIFF/WAVE file");
  }
  bool have_format = false;
  AudioClip clip;
  // Walk the chunks: id (4), size (4), payload padded to an even length.
  std::size_t at = 12;
  while (at + 8 <= bytes.size()) {
    const std::string id = bytes.substr(at, 4);
    const std::uint32_t size = GetU32(bytes, at + 4);
    const std::size_t payload = at + 8;
    if (payload + size > bytes.size()) throw fail("chunk '" + id + "' is truncated");
    if (id == "fmt ") {
      if (size < 16) throw fail("fmt chunk is too short");
      const std::uint16_t format = GetU16(bytes, payload);
      const std::uint16_t channels = GetU16(bytes, payload + 2);
      const std::uint32_t rate = GetU32(bytes, payload + 4);
      const std::uint16_t bits = GetU16(bytes, payload + 14);
      if (format != kFormatPcm || channels != kChannels || bits != kBitsPerSample) {
        throw fail("format " + std::to_string(format) + ", " + std::to_string(channels) +
                   " channels, " + std::to_string(bits) + " bits; only 16-bit mono PCM is supported");
      }
      if (rate == 0 || rate > static_cast<std::uint32_t>(std::numeric_limits<int>::max())) {
        throw fail("invalid sample rate " + std::to_string(rate));
      }
      clip.sample_rate_hz = static_cast<int>(rate);
      have_format = true;
    } else if (id == "data") {
      if (!have_format) throw fail("data chunk before fmt chunk");
      if (size % 2 != 0) throw fail("data chunk has an odd number of bytes");
      clip.samples.resize(size / 2);
      for (std::size_t i = 0; i < clip.samples.size(); ++i) {
        clip.samples[i] = static_cast<std::int16_t>(GetU16(bytes, payload + 2 * i));
      }
      return clip;
    }
    at = payload + size + (size % 2);
  }
  throw fail(have_format ? "no data chunk" : "no fmt chunk");
}

}  // namespace handshare::speech
