// Replays a fuzz corpus through one target without libFuzzer: every file under the folders and
// files given, in name order, once. Built with AddressSanitizer and UndefinedBehaviorSanitizer
// by the normal (gcc) build, so ctest replays every corpus on every test run (fuzz.* tests); a
// report aborts the run with the input's name printed just before.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

#include "fuzz_support.hpp"

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: %s CORPUS_DIR_OR_FILE...\n", argv[0]);
    return 2;
  }
  std::vector<std::filesystem::path> inputs;
  for (int i = 1; i < argc; ++i) {
    const std::filesystem::path p = argv[i];
    if (std::filesystem::is_directory(p)) {
      for (const auto& e : std::filesystem::recursive_directory_iterator(p)) {
        if (e.is_regular_file()) inputs.push_back(e.path());
      }
    } else if (std::filesystem::is_regular_file(p)) {
      inputs.push_back(p);
    } else {
      std::fprintf(stderr, "%s: %s is neither a file nor a folder\n", argv[0], p.c_str());
      return 1;
    }
  }
  if (inputs.empty()) {
    std::fprintf(stderr, "%s: no inputs under the corpus given\n", argv[0]);
    return 1;
  }
  std::sort(inputs.begin(), inputs.end());
  handshare::fuzz::show_outcomes = true;
  for (const auto& p : inputs) {
    std::ifstream in(p, std::ios::binary);
    const std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::fprintf(stderr, "input %s (%zu bytes)\n", p.c_str(), bytes.size());
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  handshare::fuzz::RemoveInputs();
  std::printf("%s: %zu inputs replayed, no finding\n", argv[0], inputs.size());
  return 0;
}
