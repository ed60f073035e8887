// Fuzz target: a session recording (SQLite, session_record) checked by VerifyRecording, which
// session_play --check runs and which reads every sample as the player would.
#include "fuzz_support.hpp"
#include "handshare/world_server/recording.hpp"
#include "handshare/world_server/session_log.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace s = handshare::server;
  const auto file = handshare::fuzz::WriteInput("session.rec", data, size);
  handshare::fuzz::ExpectOnly<s::RecordingError, s::SessionLogError>([&] { s::VerifyRecording(file); });
  return 0;
}
