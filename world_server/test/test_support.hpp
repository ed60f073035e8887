#pragma once
// Helpers shared by the world server's tests: a fresh folder per test under $TMPDIR, removed
// (permissions restored first) at the end; fixed times; the message of a SessionLogError.
#include <stdlib.h>
#include <sys/stat.h>

#include <cstdint>
#include <filesystem>
#include <functional>
#include <stdexcept>
#include <string>

#include "handshare/world_server/session_log.hpp"

namespace handshare::server::testing {

class TempDir {
 public:
  TempDir() {
    std::string pattern = (std::filesystem::temp_directory_path() / "handshare_ws_XXXXXX").string();
    if (!mkdtemp(pattern.data())) throw std::runtime_error("mkdtemp failed for " + pattern);
    path_ = pattern;
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::permissions(path_, std::filesystem::perms::owner_all, ec);
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

inline constexpr std::uint64_t kT0 = 1'700'000'000'000'000'000ULL;  // a fixed Unix time [ns]
inline constexpr std::uint64_t kSecond = 1'000'000'000ULL;

/// what() of the SessionLogError that f throws, or "<no SessionLogError>".
inline std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const SessionLogError& e) {
    return e.what();
  }
  return "<no SessionLogError>";
}

}  // namespace handshare::server::testing
