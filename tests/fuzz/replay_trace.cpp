// Fuzz target: a device-state trace (haptic_node --trace CSV) read by the replay device's
// ReplayLog::Parse.
#include <string>

#include "fuzz_support.hpp"
#include "handshare/haptic/replay.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  handshare::fuzz::ExpectOnly<handshare::haptic::ReplayError>(
      [&] { handshare::haptic::ReplayLog::Parse(text, "fuzz_trace.csv"); });
  return 0;
}
