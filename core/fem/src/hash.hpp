#pragma once
// Internal: a fast, non-cryptographic 64-bit hash for cache validation (input hash and payload
// checksum). Word-wise FNV-1a with an extra shift-xor so high input bits reach low output bits.
// It detects accidental corruption and stale inputs, not tampering.

#include <cstddef>
#include <cstdint>
#include <algorithm>
#include <cstring>
#include <span>

namespace handshare::fem::detail {

class Hasher64 {
 public:
  void Bytes(const void* data, std::size_t n) noexcept {
    const auto* p = static_cast<const unsigned char*>(data);
    // Finish a partial word left from the previous call.
    if (fill_ > 0) {
      const std::size_t take = std::min<std::size_t>(8 - fill_, n);
      std::memcpy(buf_ + fill_, p, take);
      fill_ += take;
      p += take;
      n -= take;
      if (fill_ < 8) return;
      std::uint64_t w;
      std::memcpy(&w, buf_, 8);
      Word(w);
      fill_ = 0;
    }
    while (n >= 8) {
      std::uint64_t w;
      std::memcpy(&w, p, 8);
      Word(w);
      p += 8;
      n -= 8;
    }
    std::memcpy(buf_, p, n);
    fill_ = n;
  }
  template <class T>
  void Pod(const T& v) noexcept {
    Bytes(&v, sizeof(T));
  }
  template <class T>
  void Span(std::span<const T> s) noexcept {
    Pod(static_cast<std::uint64_t>(s.size()));
    Bytes(s.data(), s.size_bytes());
  }
  std::uint64_t digest() const noexcept {
    std::uint64_t h = h_;
    for (std::size_t i = 0; i < fill_; ++i) h = Mix(h, buf_[i]);
    h = Mix(h, total_ + static_cast<std::uint64_t>(fill_));
    return h == 0 ? 1 : h;  // 0 means "no hash" in the API.
  }

 private:
  static std::uint64_t Mix(std::uint64_t h, std::uint64_t w) noexcept {
    h = (h ^ w) * 0x100000001b3ull;
    return h ^ (h >> 29);
  }
  void Word(std::uint64_t w) noexcept {
    h_ = Mix(h_, w);
    total_ += 8;
  }
  std::uint64_t h_ = 0xcbf29ce484222325ull;
  std::uint64_t total_ = 0;
  unsigned char buf_[8] = {};
  std::size_t fill_ = 0;
};

}  // namespace handshare::fem::detail
