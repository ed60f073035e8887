// Fuzz target: a session log (SQLite) read by the world server when it resumes
// (FindResumePoint) and by session_report (ListSessions, ReadReport, both printed).
#include <sstream>

#include "fuzz_support.hpp"
#include "handshare/world_server/session_log.hpp"
#include "handshare/world_server/session_report.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  namespace s = handshare::server;
  const auto file = handshare::fuzz::WriteInput("session.db", data, size);
  handshare::fuzz::ExpectOnly<s::SessionLogError>([&] {
    for (const auto& summary : s::ListSessions(file)) {
      // A resume point of any age (now: the year 2033).
      s::FindResumePoint(file, summary.name, 2'000'000'000'000'000'000ULL, 2'000'000'000'000'000'000ULL);
      std::ostringstream out;
      const auto report = s::ReadReport(file, summary.id);
      s::PrintReport(out, report);
      s::PrintReportCsv(out, report);
    }
  });
  return 0;
}
