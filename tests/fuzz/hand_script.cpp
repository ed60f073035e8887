// Fuzz target: a simulated hand's script (haptic_node --script) read by HandScript::Parse, and
// every pose it gives evaluated over its span (the haptic loop reads them at 1 kHz).
#include <cmath>
#include <string>

#include "fuzz_support.hpp"
#include "handshare/haptic/sim_hand.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  handshare::fuzz::ExpectOnly<handshare::haptic::ScriptError>([&] {
    const auto script = handshare::haptic::HandScript::Parse(text, "fuzz.hand");
    for (double t = -1.0; t < 120.0; t += 0.37) {
      for (const auto& p : handshare::haptic::SimFingertips(script.PoseAt(t))) {
        if (!p.allFinite()) {
          std::fprintf(stderr, "fuzz: finding: a parsed script gives a non-finite fingertip at t = %g s\n", t);
          std::abort();
        }
      }
    }
  });
  return 0;
}
