// Fuzz target: a HIRO II configuration (JSON) read by hiro::HiroModel::Parse.
#include <string>

#include "fuzz_support.hpp"
#include "handshare/hiro/hiro_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  handshare::fuzz::ExpectOnly<handshare::hiro::ConfigError>(
      [&] { handshare::hiro::HiroModel::Parse(text, "fuzz_hiro.json"); });
  return 0;
}
