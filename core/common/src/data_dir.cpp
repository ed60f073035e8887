#include "handshare/common/data_dir.hpp"

#include <cstdlib>
#include <string_view>
#include <system_error>

namespace handshare::common {

namespace {

// Both compiled in by core/common/CMakeLists.txt.
constexpr const char* kSourceDir = HANDSHARE_SOURCE_DIR;
constexpr const char* kBinToData = HANDSHARE_BIN_TO_DATA;  // "../share/handshare" by default

std::filesystem::path Find(std::string_view installed, std::string_view source) {
  const auto& data = InstalledDataDir();
  return data.empty() ? std::filesystem::path(kSourceDir) / source : data / installed;
}

}  // namespace

const std::filesystem::path& InstalledDataDir() {
  static const std::filesystem::path dir = [] {
    std::error_code ec;
    const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    if (ec || exe.empty()) return std::filesystem::path();
    const auto candidate = (exe.parent_path() / kBinToData).lexically_normal();
    return std::filesystem::is_directory(candidate, ec) ? candidate : std::filesystem::path();
  }();
  return dir;
}

std::filesystem::path AssetsDir() {
  if (const char* env = std::getenv("HANDSHARE_ASSETS"); env != nullptr && *env != '\0') return env;
  return Find("assets", "assets");
}

std::filesystem::path QosDir() { return Find("qos", "deploy/qos"); }

std::filesystem::path HandScriptsDir() { return Find("scripts", "haptic_node/scripts"); }

}  // namespace handshare::common
