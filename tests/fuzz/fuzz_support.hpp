#pragma once
// Shared by the fuzz targets of tests/fuzz (docs/security.md, "Hostile files").
//
// Each target feeds one input to one reader of outside data. The reader may refuse the input
// only with its own error type (which names the file and the place); any other exception, a
// crash, a hang or a sanitizer report is a finding. Readers that take a path get the input
// written to a file of this process's own (inputs never share a file across processes).
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>
#include <typeinfo>

namespace handshare::fuzz {

/// A file under the temporary folder named after this process and `name` (a relative path,
/// with its extension), holding `size` bytes of `data`. Reused across inputs of one process.
inline std::filesystem::path WriteInput(const std::string& name, const std::uint8_t* data, std::size_t size) {
  static const std::filesystem::path dir = [] {
    auto d = std::filesystem::temp_directory_path() / ("handshare-fuzz-" + std::to_string(getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  const auto path = dir / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) {
    std::fprintf(stderr, "fuzz: cannot write %s\n", path.c_str());
    std::abort();
  }
  return path;
}

/// Removes this process's input files (the replay driver calls it at exit).
inline void RemoveInputs() {
  std::error_code ignored;
  std::filesystem::remove_all(std::filesystem::temp_directory_path() / ("handshare-fuzz-" + std::to_string(getpid())),
                              ignored);
}

/// Set by the corpus replay (not under libFuzzer): each input's outcome is printed.
inline bool show_outcomes = false;

/// Runs `read`; returns normally if it succeeds or throws one of `Refusals`, aborts (a finding)
/// on any other exception, printing its type and message.
template <class... Refusals, class F>
void ExpectOnly(F&& read) {
  try {
    read();
    if (show_outcomes) std::fprintf(stderr, "  read\n");
  } catch (const std::exception& e) {
    if ((dynamic_cast<const Refusals*>(&e) || ...)) {
      if (show_outcomes) std::fprintf(stderr, "  refused: %s\n", e.what());
      return;
    }
    std::fprintf(stderr, "fuzz: finding: %s escaped the reader: %s\n", typeid(e).name(), e.what());
    std::abort();
  }
}

}  // namespace handshare::fuzz

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);
